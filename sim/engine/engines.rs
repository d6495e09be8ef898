//! Which engines a validation runs, by name.

/// Which physics engines a validation runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Engines {
    /// rapier (multibody, f32).
    pub rapier: bool,
    /// MuJoCo (the official library).
    pub mujoco: bool,
}

impl Engines {
    /// The engines named (`rapier`, `mujoco`); no name gives no engine.
    ///
    /// # Errors
    /// The first name that is not an engine.
    pub fn from_names<'a>(names: impl IntoIterator<Item = &'a str>) -> Result<Self, String> {
        let mut engines = Self {
            rapier: false,
            mujoco: false,
        };
        for name in names {
            match name {
                "rapier" => engines.rapier = true,
                "mujoco" => engines.mujoco = true,
                other => return Err(other.to_string()),
            }
        }
        Ok(engines)
    }

    /// The names, comma-separated (`rapier,mujoco`), or `none`.
    pub fn name(self) -> String {
        match (self.rapier, self.mujoco) {
            (true, true) => "rapier,mujoco".into(),
            (true, false) => "rapier".into(),
            (false, true) => "mujoco".into(),
            (false, false) => "none".into(),
        }
    }
}

impl std::str::FromStr for Engines {
    type Err = String;

    /// A comma-separated list of engines (`rapier,mujoco`, `rapier`, `mujoco`), or `none`; the
    /// error names what is not an engine and what was expected.
    fn from_str(text: &str) -> Result<Self, Self::Err> {
        let names: Vec<&str> = if text.trim() == "none" {
            Vec::new()
        } else {
            text.split(',').map(str::trim).collect()
        };
        Self::from_names(names).map_err(|other| format!("unknown engine `{other}`; expected rapier,mujoco, rapier, mujoco or none"))
    }
}

impl Default for Engines {
    fn default() -> Self {
        Self {
            rapier: true,
            mujoco: true,
        }
    }
}
