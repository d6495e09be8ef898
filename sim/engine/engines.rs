//! The physics engines behind one seam: what the pipeline asks of an engine ([`Engine`]), the
//! engines there are ([`ENGINES`]: a new engine is a file with its runs and one entry there),
//! and which of them a validation runs ([`Engines`], by name).

use super::{EngineError, EngineRun, Gains, RunOptions, StaticLoad};
use crate::collide::CollisionWorld;
use crate::model::Model;
use crate::plan::TimedPath;
use crate::scenario::Scenario;

/// A physics engine the trajectory is run in.
pub trait Engine: Sync {
    /// Its name on the command line and in reports.
    fn name(&self) -> &'static str;

    /// Its name in prose (`MuJoCo`).
    fn label(&self) -> &'static str {
        self.name()
    }

    /// What it approximates that exact geometry does not, for findings that blame a contact or
    /// a missed hold on the engine rather than the design.
    fn approximation(&self) -> &'static str {
        "the engine's geometric approximation"
    }

    /// What its peak effort in motion is.
    fn effort(&self) -> Effort {
        Effort {
            estimate: false,
            note: "the engine's actuator force",
        }
    }

    /// Follows the timed path under the gains' position control, gravity on.
    ///
    /// # Errors
    /// The engine refusing the model, the path or the options.
    fn run(
        &self,
        model: &Model,
        scenario: &Scenario,
        world: &CollisionWorld,
        path: &TimedPath,
        gains: &Gains,
        opts: &RunOptions,
    ) -> Result<EngineRun, EngineError>;

    /// Sets the positions of `samples` (replay clock, configuration) one after the other and
    /// records the contacts: the kinematic replay.
    ///
    /// # Errors
    /// As [`Engine::run`].
    fn replay(
        &self,
        model: &Model,
        scenario: &Scenario,
        world: &CollisionWorld,
        samples: &[(f64, Vec<f64>)],
        opts: &RunOptions,
    ) -> Result<EngineRun, EngineError>;

    /// The gravity torques at `configurations` judged against the ratings, when the engine
    /// computes them independently of our dynamics (a cross-check); `None` otherwise.
    ///
    /// # Errors
    /// As [`Engine::run`].
    fn static_load(
        &self,
        _model: &Model,
        _configurations: &mut dyn Iterator<Item = Vec<f64>>,
        _gravity_m_s2: f64,
    ) -> Option<Result<StaticLoad, EngineError>> {
        None
    }
}

/// What an engine's peak effort in motion is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Effort {
    /// An estimate rather than the force the engine applied.
    pub estimate: bool,
    /// What the number is, for a reader comparing it with a rating.
    pub note: &'static str,
}

/// rapier (multibody, f32); its contacts are re-measured in exact geometry before they count.
pub struct Rapier;

impl Engine for Rapier {
    fn name(&self) -> &'static str {
        "rapier"
    }

    fn approximation(&self) -> &'static str {
        "rapier collides in f32, with up to centimetres of phantom depth on cylinders"
    }

    fn effort(&self) -> Effort {
        Effort {
            estimate: true,
            note: "an estimate: rapier does not report multibody motor impulses, so this is the control law evaluated after each step, stiff gains and all",
        }
    }

    fn run(
        &self,
        model: &Model,
        scenario: &Scenario,
        world: &CollisionWorld,
        path: &TimedPath,
        gains: &Gains,
        opts: &RunOptions,
    ) -> Result<EngineRun, EngineError> {
        super::run_rapier(model, scenario, world, path, gains, opts)
    }

    fn replay(
        &self,
        model: &Model,
        scenario: &Scenario,
        world: &CollisionWorld,
        samples: &[(f64, Vec<f64>)],
        opts: &RunOptions,
    ) -> Result<EngineRun, EngineError> {
        super::replay_rapier(model, scenario, world, samples, opts)
    }
}

/// MuJoCo (the official library): also the static load's cross-check.
pub struct Mujoco;

impl Engine for Mujoco {
    fn name(&self) -> &'static str {
        "mujoco"
    }

    fn label(&self) -> &'static str {
        "MuJoCo"
    }

    fn approximation(&self) -> &'static str {
        "MuJoCo collides meshes as convex pieces (up to about 12 mm beyond a UR5 link's surface) and cylinders through its general convex solver"
    }

    fn effort(&self) -> Effort {
        Effort {
            estimate: false,
            note: "MuJoCo's actuator force; the controller's stiffness in motion, not the static load",
        }
    }

    fn run(
        &self,
        model: &Model,
        scenario: &Scenario,
        world: &CollisionWorld,
        path: &TimedPath,
        gains: &Gains,
        opts: &RunOptions,
    ) -> Result<EngineRun, EngineError> {
        super::run_mujoco(model, scenario, world, path, gains, opts)
    }

    fn replay(
        &self,
        model: &Model,
        scenario: &Scenario,
        world: &CollisionWorld,
        samples: &[(f64, Vec<f64>)],
        opts: &RunOptions,
    ) -> Result<EngineRun, EngineError> {
        super::replay_mujoco(model, scenario, world, samples, opts)
    }

    fn static_load(
        &self,
        model: &Model,
        configurations: &mut dyn Iterator<Item = Vec<f64>>,
        gravity_m_s2: f64,
    ) -> Option<Result<StaticLoad, EngineError>> {
        let load = super::static_load(model, configurations, gravity_m_s2);
        Some(load.map(|load| StaticLoad {
            cross_checked_by: Some(self.label()),
            ..load
        }))
    }
}

/// Every engine, in the order reports list them.
pub static ENGINES: &[&dyn Engine] = &[&Rapier, &Mujoco];

/// The engine called `name` ([`Engine::name`]).
pub fn find(name: &str) -> Option<&'static dyn Engine> {
    ENGINES.iter().find(|e| e.name() == name).copied()
}

/// Which of [`ENGINES`] a validation runs (a set, kept in their order).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Engines {
    /// Bit `k` set: `ENGINES[k]` runs.
    chosen: u32,
}

impl Engines {
    /// No engine.
    pub fn none() -> Self {
        Self { chosen: 0 }
    }

    /// Every engine there is.
    pub fn all() -> Self {
        Self {
            chosen: (1 << ENGINES.len()) - 1,
        }
    }

    /// The engines named (each a [`Engine::name`]); no name gives no engine.
    ///
    /// # Errors
    /// A message naming the first name that is not an engine and what was expected.
    pub fn from_names<'a>(names: impl IntoIterator<Item = &'a str>) -> Result<Self, String> {
        let mut engines = Self::none();
        for name in names {
            let k = ENGINES.iter().position(|e| e.name() == name).ok_or_else(|| {
                let each: Vec<&str> = ENGINES.iter().map(|e| e.name()).collect();
                format!("unknown engine `{name}`; expected {}, {} or none", each.join(","), each.join(", "))
            })?;
            engines.chosen |= 1 << k;
        }
        Ok(engines)
    }

    /// Whether no engine runs.
    pub fn is_empty(self) -> bool {
        self.chosen == 0
    }

    /// The engines that run, in [`ENGINES`]' order.
    pub fn selected(self) -> impl Iterator<Item = &'static dyn Engine> {
        ENGINES
            .iter()
            .enumerate()
            .filter(move |(k, _)| self.chosen & (1 << k) != 0)
            .map(|(_, e)| *e)
    }

    /// The names, comma-separated (`rapier,mujoco`), or `none`.
    pub fn name(self) -> String {
        if self.is_empty() {
            return "none".into();
        }
        self.selected().map(|e| e.name()).collect::<Vec<_>>().join(",")
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
        Self::from_names(names)
    }
}

impl std::fmt::Display for Engines {
    /// As [`Engines::name`]: what `from_str` reads back.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.name())
    }
}

impl Default for Engines {
    fn default() -> Self {
        Self::all()
    }
}
