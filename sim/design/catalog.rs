//! The reference module catalog, the industrial presets and the economic constraints, from
//! `shared/reference/robots.md` (the paper "A Design Co-Pilot for Task-Tailored Manipulators").

use serde::{Deserialize, Serialize};
use std::f64::consts::{FRAC_PI_2, PI};

/// Diameter of every link tube, joint module and no-link sphere (m).
pub const LINK_DIAMETER_M: f64 = 0.12;
/// Length of a joint module housing along its axis (m).
pub const JOINT_MODULE_LENGTH_M: f64 = 0.12;
/// Mass of one joint module (kg).
pub const JOINT_MODULE_KG: f64 = 1.8;
/// Linear density of the aluminium link tubes (kg per metre of tube).
pub const TUBE_KG_PER_M: f64 = 3.0;
/// Rated torque of a joint module (N m).
pub const JOINT_MODULE_RATED_TORQUE_NM: f64 = 60.0;
/// Maximum speed of a joint module (rad/s).
pub const JOINT_MODULE_MAX_SPEED: f64 = PI;
/// Joint module limits (rad): +-2 pi.
pub const JOINT_MODULE_LIMIT: f64 = 2.0 * PI;
/// Tolerance on economic-mode constraints.
pub const ECONOMIC_TOLERANCE: f64 = 1e-9;
/// How far (absolute, in m or rad) an economic value may lie from one of the sets' named values
/// (0, the interval bounds, +-pi/2) and still be read as that value. Designs come from float32
/// generators (PyTorch's default dtype): float32 spacing is 1.2e-7 near pi/2 and 7.5e-9 near 0.1,
/// so float32's rounding of pi/2 lands 4.4e-8 away; 1e-6 covers a few ulps of that and is still
/// far below any length or angle that matters to the robot.
pub const FLOAT32_SNAP: f64 = 1e-6;

/// One connection-slot option of the modular catalog.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum SlotOption {
    /// Next joint on the output flange; consecutive axes orthogonal.
    #[serde(rename = "direct")]
    Direct,
    /// Straight tube, 0.15 m, axes orthogonal.
    #[serde(rename = "I-short")]
    IShort,
    /// Straight tube, 0.30 m, axes orthogonal.
    #[serde(rename = "I-long")]
    ILong,
    /// Elbow tube, offset 0.20 m, axes parallel.
    #[serde(rename = "L-short")]
    LShort,
    /// Elbow tube, offset 0.35 m, axes parallel.
    #[serde(rename = "L-long")]
    LLong,
}

impl SlotOption {
    /// Every option, in catalog order.
    pub const ALL: [SlotOption; 5] = [Self::Direct, Self::IShort, Self::ILong, Self::LShort, Self::LLong];

    /// The DH row `(d, a, alpha)` of this option.
    pub fn dh(self) -> [f64; 3] {
        match self {
            Self::Direct => [0.10, 0.0, FRAC_PI_2],
            Self::IShort => [0.25, 0.0, FRAC_PI_2],
            Self::ILong => [0.40, 0.0, FRAC_PI_2],
            Self::LShort => [0.10, 0.20, 0.0],
            Self::LLong => [0.10, 0.35, 0.0],
        }
    }

    /// The short code of catalog ids (`modular6/D-Ls-Il-D-Is-Ll`).
    pub fn code(self) -> &'static str {
        match self {
            Self::Direct => "D",
            Self::IShort => "Is",
            Self::ILong => "Il",
            Self::LShort => "Ls",
            Self::LLong => "Ll",
        }
    }

    /// The name used in design files.
    pub fn name(self) -> &'static str {
        match self {
            Self::Direct => "direct",
            Self::IShort => "I-short",
            Self::ILong => "I-long",
            Self::LShort => "L-short",
            Self::LLong => "L-long",
        }
    }
}

/// A robot named by its catalog id, as `sweep` and `ga` print them.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum CatalogId {
    /// `modularN/C1-...-CN`: N slots of the module catalog, by [`SlotOption::code`].
    Modular(Vec<SlotOption>),
    /// `preset/NAME`: an industrial preset by [`Preset::name`].
    Preset(Preset),
}

/// The id of the modular robot of `slots`.
pub fn modular_id(slots: &[SlotOption]) -> String {
    let codes: Vec<&str> = slots.iter().map(|s| s.code()).collect();
    format!("modular{}/{}", slots.len(), codes.join("-"))
}

/// The id of a preset.
pub fn preset_id(preset: Preset) -> String {
    format!("preset/{}", preset.name())
}

/// Reads a catalog id: `Ok(None)` for text that does not look like one (`modularN/...`,
/// `preset/...`), the message for one that looks like it but names no robot.
///
/// # Errors
/// What is wrong and what was expected.
pub fn parse_id(text: &str) -> Result<Option<CatalogId>, String> {
    if let Some(name) = text.strip_prefix("preset/") {
        return match Preset::ALL.into_iter().find(|p| p.name() == name) {
            Some(preset) => Ok(Some(CatalogId::Preset(preset))),
            None => {
                let names: Vec<String> = Preset::ALL.into_iter().map(preset_id).collect();
                Err(format!("no such preset; expected one of {}", names.join(", ")))
            }
        };
    }
    let Some((count, codes)) = text.strip_prefix("modular").and_then(|rest| rest.split_once('/')) else {
        return Ok(None);
    };
    if count.is_empty() || !count.bytes().all(|b| b.is_ascii_digit()) {
        return Ok(None);
    }
    let expected = || {
        let all: Vec<&str> = SlotOption::ALL.iter().map(|s| s.code()).collect();
        format!("expected modularN/ and N slot codes joined by `-`, each one of {}", all.join(", "))
    };
    let slots = codes
        .split('-')
        .map(|code| SlotOption::ALL.into_iter().find(|s| s.code() == code).ok_or(code))
        .collect::<Result<Vec<_>, _>>()
        .map_err(|code| format!("unknown slot code `{code}`; {}", expected()))?;
    if count.parse::<usize>().ok() != Some(slots.len()) {
        return Err(format!("says {count} slots and lists {}; {}", slots.len(), expected()));
    }
    Ok(Some(CatalogId::Modular(slots)))
}

/// Industrial robots whose published DH tables the paper used as baselines.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Preset {
    /// Universal Robots UR5e.
    #[serde(rename = "UR5e")]
    Ur5e,
    /// Universal Robots UR10e.
    #[serde(rename = "UR10e")]
    Ur10e,
    /// Universal Robots UR15.
    #[serde(rename = "UR15")]
    Ur15,
    /// Universal Robots UR20.
    #[serde(rename = "UR20")]
    Ur20,
    /// ABB IRB 2600-12/1.65.
    #[serde(rename = "ABB-IRB-2600")]
    AbbIrb2600,
}

impl Preset {
    /// Every preset, in the order of the paper's tables.
    pub const ALL: [Preset; 5] = [Self::Ur5e, Self::Ur10e, Self::Ur15, Self::Ur20, Self::AbbIrb2600];

    /// The name used in design files.
    pub fn name(self) -> &'static str {
        match self {
            Self::Ur5e => "UR5e",
            Self::Ur10e => "UR10e",
            Self::Ur15 => "UR15",
            Self::Ur20 => "UR20",
            Self::AbbIrb2600 => "ABB-IRB-2600",
        }
    }

    /// DH rows `(d, a, alpha)` per joint, standard convention.
    pub fn dh(self) -> Vec<[f64; 3]> {
        let ur = |d1: f64, a2: f64, a3: f64, d4: f64, d5: f64, d6: f64| {
            vec![
                [d1, 0.0, FRAC_PI_2],
                [0.0, a2, 0.0],
                [0.0, a3, 0.0],
                [d4, 0.0, FRAC_PI_2],
                [d5, 0.0, -FRAC_PI_2],
                [d6, 0.0, 0.0],
            ]
        };
        match self {
            Self::Ur5e => ur(0.1625, -0.425, -0.3922, 0.1333, 0.0997, 0.0996),
            Self::Ur10e => ur(0.1807, -0.6127, -0.57155, 0.17415, 0.11985, 0.11655),
            // Universal Robots' DH table for the UR15 as we know it from their DH page;
            // robots.md does not reproduce it and no second source here could confirm it: check
            // it before quoting UR15 numbers.
            Self::Ur15 => ur(0.2186, -0.6475, -0.5164, 0.1746, 0.1201, 0.1153),
            Self::Ur20 => ur(0.2363, -0.8620, -0.7287, 0.2010, 0.1593, 0.1543),
            Self::AbbIrb2600 => vec![
                [0.445, 0.150, -FRAC_PI_2],
                [0.0, 0.700, 0.0],
                [0.0, 0.115, -FRAC_PI_2],
                [0.795, 0.0, FRAC_PI_2],
                [0.0, 0.0, -FRAC_PI_2],
                [0.085, 0.0, 0.0],
            ],
        }
    }
}

/// Which economic constraint a value breaks, if any: `d` in {0} U [0.1, 0.4]; `a` in
/// {0} U [-0.4, -0.1] U [0.1, 0.4]; `alpha` in {0, +pi/2, -pi/2}.
pub fn economic_violation(parameter: &str, value: f64) -> Option<&'static str> {
    let near = |target: f64| (value - target).abs() <= ECONOMIC_TOLERANCE;
    let within = |lo: f64, hi: f64| value >= lo - ECONOMIC_TOLERANCE && value <= hi + ECONOMIC_TOLERANCE;
    let ok = match parameter {
        "d" => near(0.0) || within(0.1, 0.4),
        "a" => near(0.0) || within(0.1, 0.4) || within(-0.4, -0.1),
        "alpha" => near(0.0) || near(FRAC_PI_2) || near(-FRAC_PI_2),
        _ => true,
    };
    if ok {
        return None;
    }
    Some(match parameter {
        "d" => "{0} U [0.1, 0.4] m",
        "a" => "{0} U [-0.4, -0.1] U [0.1, 0.4] m",
        _ => "{0, +pi/2, -pi/2} rad",
    })
}

/// A named value of an economic set that a nearby value is read as.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EconomicSnap {
    /// The value used (m or rad).
    pub value: f64,
    /// How the value is written in messages (`-pi/2`, `0.1`).
    pub name: &'static str,
}

/// The named value of the economic set of `parameter` (`d`, `a` or `alpha`) that `value` lies
/// within [`FLOAT32_SNAP`] of without being it exactly: 0, the bounds of the intervals, +-pi/2.
/// `None` for a value that is exactly a named value or not near one (an interval's inside stays as
/// written), and for other parameters.
pub fn economic_snap(parameter: &str, value: f64) -> Option<EconomicSnap> {
    let named: &[(f64, &'static str)] = match parameter {
        "d" => &[(0.0, "0"), (0.1, "0.1"), (0.4, "0.4")],
        "a" => &[(0.0, "0"), (0.1, "0.1"), (0.4, "0.4"), (-0.1, "-0.1"), (-0.4, "-0.4")],
        "alpha" => &[(0.0, "0"), (FRAC_PI_2, "pi/2"), (-FRAC_PI_2, "-pi/2")],
        _ => &[],
    };
    named
        .iter()
        .find(|(target, _)| value != *target && (value - target).abs() <= FLOAT32_SNAP)
        .map(|&(value, name)| EconomicSnap { value, name })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_modular_option_is_economic() {
        for option in SlotOption::ALL {
            let [d, a, alpha] = option.dh();
            assert_eq!(economic_violation("d", d), None, "{option:?}");
            assert_eq!(economic_violation("a", a), None, "{option:?}");
            assert_eq!(economic_violation("alpha", alpha), None, "{option:?}");
        }
    }

    #[test]
    fn economic_bounds_are_inclusive_within_tolerance() {
        assert_eq!(economic_violation("d", 0.4 + 1e-10), None);
        assert!(economic_violation("d", 0.4 + 1e-8).is_some());
        assert!(economic_violation("d", 0.05).is_some());
        assert!(economic_violation("a", -0.05).is_some());
        assert_eq!(economic_violation("a", -0.25), None);
        assert!(economic_violation("alpha", 1.0).is_some());
    }

    #[test]
    fn float32_pi_over_2_snaps_to_pi_over_2() {
        let written = f64::from(FRAC_PI_2 as f32);
        assert_eq!(
            economic_snap("alpha", -written),
            Some(EconomicSnap {
                value: -FRAC_PI_2,
                name: "-pi/2"
            })
        );
        assert_eq!(economic_snap("alpha", FRAC_PI_2), None, "an exact value is not snapped");
        assert_eq!(economic_snap("alpha", FRAC_PI_2 + 2e-6), None);
    }

    #[test]
    fn bounds_snap_from_both_sides_and_insides_stay() {
        assert_eq!(economic_snap("d", 0.1000000015).map(|s| s.value), Some(0.1));
        assert_eq!(economic_snap("d", 0.4 + 5e-7).map(|s| s.value), Some(0.4));
        assert_eq!(economic_snap("a", -0.1 + 5e-7).map(|s| s.value), Some(-0.1));
        assert_eq!(economic_snap("a", 3e-7).map(|s| s.value), Some(0.0));
        assert_eq!(economic_snap("d", 0.25 + 1e-7), None, "inside an interval, not near a bound");
        assert_eq!(economic_snap("d", -0.1 + 1e-7), None, "d has no negative interval");
        assert_eq!(economic_snap("max_velocity", 1e-7), None);
    }
}
