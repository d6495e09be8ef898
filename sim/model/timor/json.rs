//! The JSON that Timor writes: Python's `json` module, which writes `Infinity`, `-Infinity` and
//! `NaN` for non-finite floats (a joint without a torque rating has `"peakTorque": Infinity`).
//! serde_json rejects those tokens, so they are quoted before parsing ([`quote_non_finite`]) and
//! [`Num`] reads a number or one of the quoted words. Lines stay where they were, so serde's
//! line numbers name the line of the file.

use nalgebra::{Isometry3, Matrix3, Rotation3, Translation3, UnitQuaternion, Vector3};
use serde::de::{self, Deserializer, Visitor};
use serde::Deserialize;

/// The words Python writes for non-finite floats, and their values.
const NON_FINITE: [(&str, f64); 3] = [("-Infinity", f64::NEG_INFINITY), ("Infinity", f64::INFINITY), ("NaN", f64::NAN)];

/// `text` with every `Infinity`, `-Infinity` and `NaN` outside strings put in quotes.
pub(crate) fn quote_non_finite(text: &str) -> String {
    let bytes = text.as_bytes();
    let mut out = String::with_capacity(text.len() + 16);
    let mut in_string = false;
    let mut escaped = false;
    let mut i = 0;
    let mut copied = 0;
    while i < bytes.len() {
        let b = bytes[i];
        if in_string {
            match (escaped, b) {
                (true, _) => escaped = false,
                (false, b'\\') => escaped = true,
                (false, b'"') => in_string = false,
                _ => {}
            }
            i += 1;
            continue;
        }
        if b == b'"' {
            in_string = true;
            i += 1;
            continue;
        }
        // Bytes, not `str` slices: `i` may sit inside a multi-byte character (a BOM); a match is
        // ASCII, so the slices below fall on character boundaries.
        let word = NON_FINITE.iter().map(|(w, _)| *w).find(|w| bytes[i..].starts_with(w.as_bytes()));
        match word {
            Some(word) if i == 0 || !bytes[i - 1].is_ascii_alphanumeric() => {
                out.push_str(&text[copied..i]);
                out.push('"');
                out.push_str(word);
                out.push('"');
                i += word.len();
                copied = i;
            }
            _ => i += 1,
        }
    }
    out.push_str(&text[copied..]);
    out
}

/// A number as Timor writes it: a JSON number or a quoted non-finite word.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Num(pub f64);

impl<'de> Deserialize<'de> for Num {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct NumVisitor;
        impl Visitor<'_> for NumVisitor {
            type Value = Num;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a number (or Infinity, -Infinity, NaN)")
            }
            fn visit_f64<E: de::Error>(self, v: f64) -> Result<Num, E> {
                Ok(Num(v))
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> Result<Num, E> {
                Ok(Num(v as f64))
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> Result<Num, E> {
                Ok(Num(v as f64))
            }
            fn visit_str<E: de::Error>(self, v: &str) -> Result<Num, E> {
                NON_FINITE
                    .iter()
                    .find(|(w, _)| *w == v)
                    .map(|(_, x)| Num(*x))
                    .ok_or_else(|| E::invalid_value(de::Unexpected::Str(v), &self))
            }
        }
        deserializer.deserialize_any(NumVisitor)
    }
}

/// An identifier Timor compares as a string (`str(...)`), written as a string or an integer.
#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub(crate) struct Id(pub String);

impl<'de> Deserialize<'de> for Id {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct IdVisitor;
        impl Visitor<'_> for IdVisitor {
            type Value = Id;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("an ID (a string or an integer)")
            }
            fn visit_str<E: de::Error>(self, v: &str) -> Result<Id, E> {
                Ok(Id(v.to_string()))
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> Result<Id, E> {
                Ok(Id(v.to_string()))
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> Result<Id, E> {
                Ok(Id(v.to_string()))
            }
        }
        deserializer.deserialize_any(IdVisitor)
    }
}

impl std::fmt::Display for Id {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

/// One element or a list of them: Timor accepts both wherever a list is expected.
#[derive(Debug, Clone, Deserialize)]
#[serde(untagged)]
pub(crate) enum OneOrMany<T> {
    /// A single element, written without brackets.
    One(T),
    /// A list.
    Many(Vec<T>),
}

impl<T> Default for OneOrMany<T> {
    fn default() -> Self {
        OneOrMany::Many(Vec::new())
    }
}

impl<T> OneOrMany<T> {
    pub(crate) fn into_vec(self) -> Vec<T> {
        match self {
            OneOrMany::One(x) => vec![x],
            OneOrMany::Many(v) => v,
        }
    }
}

/// A homogeneous transformation as Timor writes it: four rows of four numbers.
pub(crate) type Matrix4Rows = [[Num; 4]; 4];

/// Largest deviation from a rigid transformation that is taken for rounding (a rotation's
/// `R^T R - I`, the last row's `0 0 0 1`); Timor's files carry about 1e-16.
const RIGID_TOLERANCE: f64 = 1e-6;

/// The rigid transformation a 4x4 matrix holds; else what is wrong with it.
pub(crate) fn isometry(rows: &Matrix4Rows) -> Result<Isometry3<f64>, String> {
    let m = |r: usize, c: usize| rows[r][c].0;
    if rows.iter().flatten().any(|x| !x.0.is_finite()) {
        return Err("a 4x4 pose has a number that is not finite".into());
    }
    let last = [m(3, 0), m(3, 1), m(3, 2), m(3, 3)];
    if (last[0].abs() + last[1].abs() + last[2].abs() + (last[3] - 1.0).abs()) > RIGID_TOLERANCE {
        return Err(format!("a 4x4 pose's last row is {last:?}; expected [0, 0, 0, 1]"));
    }
    let rotation = Matrix3::from_fn(m);
    let error = (rotation.transpose() * rotation - Matrix3::identity()).abs().max();
    if error > RIGID_TOLERANCE || rotation.determinant() < 0.0 {
        return Err(format!(
            "a 4x4 pose's upper-left 3x3 block is not a rotation (|R^T R - I| = {error:.1e}, det {:.3}); expected a rigid transformation",
            rotation.determinant()
        ));
    }
    // Re-orthonormalised: a rotation off by rounding would otherwise compound along the chain.
    let rotation = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix(&rotation));
    let translation = Vector3::new(m(0, 3), m(1, 3), m(2, 3));
    if let Some(t) = translation.iter().find(|t| t.abs() > crate::limits::MAX_LENGTH_M) {
        return Err(format!(
            "a 4x4 pose's translation {t} m is beyond {} m",
            crate::limits::MAX_LENGTH_M
        ));
    }
    Ok(Isometry3::from_parts(Translation3::from(translation), rotation))
}

/// `pose` as the four rows Timor writes.
pub(crate) fn rows(pose: &Isometry3<f64>) -> [[f64; 4]; 4] {
    let h = pose.to_homogeneous();
    std::array::from_fn(|r| std::array::from_fn(|c| h[(r, c)]))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn non_finite_words_are_quoted_outside_strings_only() {
        let text = "{\"a\": Infinity, \"b\": -Infinity, \"c\": NaN, \"Infinity\": \"x NaN\", \"d\": [1, Infinity]}";
        let quoted = quote_non_finite(text);
        assert_eq!(
            quoted,
            "{\"a\": \"Infinity\", \"b\": \"-Infinity\", \"c\": \"NaN\", \"Infinity\": \"x NaN\", \"d\": [1, \"Infinity\"]}"
        );
        let values: std::collections::BTreeMap<String, serde_json::Value> = serde_json::from_str(&quoted).expect("valid JSON once quoted");
        assert_eq!(values.len(), 5);
        let a: Num = serde_json::from_value(values["a"].clone()).expect("a number");
        let b: Num = serde_json::from_value(values["b"].clone()).expect("a number");
        assert_eq!((a.0, b.0), (f64::INFINITY, f64::NEG_INFINITY));
        assert!(serde_json::from_str::<Num>("\"Inf\"").is_err());
        // Multi-byte characters (a BOM, names) around the words.
        assert_eq!(quote_non_finite("\u{feff}{\"é\": Infinity}"), "\u{feff}{\"é\": \"Infinity\"}");
        assert_eq!(quote_non_finite("ü NaN"), "ü \"NaN\"");
    }

    #[test]
    fn lines_survive_quoting() {
        let text = "{\n\"a\": Infinity,\n\"b\": oops\n}";
        let error = serde_json::from_str::<serde_json::Value>(&quote_non_finite(text)).expect_err("broken");
        assert_eq!(error.line(), 3);
    }

    #[test]
    fn a_matrix_that_is_not_rigid_is_refused() {
        let n = |v: f64| Num(v);
        let mut rows = [
            [n(1.0), n(0.0), n(0.0), n(0.1)],
            [n(0.0), n(1.0), n(0.0), n(0.0)],
            [n(0.0), n(0.0), n(1.0), n(0.0)],
            [n(0.0), n(0.0), n(0.0), n(1.0)],
        ];
        assert!(isometry(&rows).is_ok());
        rows[0][0] = n(2.0);
        assert!(isometry(&rows).expect_err("scaled").contains("not a rotation"));
        rows[0][0] = n(-1.0);
        assert!(isometry(&rows).expect_err("mirrored").contains("det"));
        rows[0][0] = n(1.0);
        rows[3][3] = n(0.5);
        assert!(isometry(&rows).expect_err("projective").contains("last row"));
    }
}
