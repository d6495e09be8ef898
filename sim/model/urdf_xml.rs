//! Checks a URDF's XML before urdf-rs reads it: urdf-rs reports a bad number as `invalid float
//! literal` with no line, keeps the last of two links of the same name, and accepts numbers of any
//! size. This pass names the element, the attribute and the line instead.

use super::ModelError;
use crate::limits;
use std::collections::HashMap;
use std::path::Path;

/// How far a number may go.
#[derive(Clone, Copy)]
enum Range {
    /// A length (m): within +-[`limits::MAX_LENGTH_M`].
    Length,
    /// A joint limit (rad or m): within +-[`limits::MAX_JOINT_LIMIT`].
    JointLimit,
    /// Anything else (angles, masses, ratings, factors): within +-[`MAX_OTHER`].
    Other,
}

/// Largest number anywhere else; past it arithmetic on ratings and masses loses meaning.
const MAX_OTHER: f64 = 1e9;

/// Attributes urdf-rs reads as numbers: element, attribute, how many numbers, their range.
const NUMBERS: &[(&str, &str, usize, Range)] = &[
    ("origin", "xyz", 3, Range::Length),
    ("origin", "rpy", 3, Range::Other),
    ("axis", "xyz", 3, Range::Other),
    ("limit", "lower", 1, Range::JointLimit),
    ("limit", "upper", 1, Range::JointLimit),
    ("limit", "effort", 1, Range::Other),
    ("limit", "velocity", 1, Range::Other),
    ("mass", "value", 1, Range::Other),
    ("inertia", "ixx", 1, Range::Other),
    ("inertia", "ixy", 1, Range::Other),
    ("inertia", "ixz", 1, Range::Other),
    ("inertia", "iyy", 1, Range::Other),
    ("inertia", "iyz", 1, Range::Other),
    ("inertia", "izz", 1, Range::Other),
    ("box", "size", 3, Range::Length),
    ("cylinder", "radius", 1, Range::Length),
    ("cylinder", "length", 1, Range::Length),
    ("capsule", "radius", 1, Range::Length),
    ("capsule", "length", 1, Range::Length),
    ("sphere", "radius", 1, Range::Length),
    ("mesh", "scale", 3, Range::Other),
    ("mimic", "multiplier", 1, Range::Other),
    ("mimic", "offset", 1, Range::Other),
    ("dynamics", "damping", 1, Range::Other),
    ("dynamics", "friction", 1, Range::Other),
    ("color", "rgba", 4, Range::Other),
];

/// Joint types URDF defines.
const JOINT_TYPES: [&str; 7] = ["revolute", "continuous", "prismatic", "fixed", "floating", "planar", "spherical"];

/// Shapes a `<geometry>` may hold (capsule: a common extension urdf-rs reads).
const SHAPES: [&str; 5] = ["box", "cylinder", "capsule", "sphere", "mesh"];

/// Checks structure, counts, names and numbers of a parsed URDF document.
///
/// # Errors
/// [`ModelError::InvalidValue`] or [`ModelError::NotATree`] naming the element, attribute and line.
pub(super) fn check(doc: &roxmltree::Document, path: &Path) -> Result<(), ModelError> {
    let line = |node: roxmltree::Node| doc.text_pos_at(node.range().start).row;
    let invalid = |element: String, message: String| ModelError::InvalidValue {
        path: path.to_path_buf(),
        element,
        message,
    };
    let root = doc.root_element();
    if root.tag_name().name() != "robot" {
        return Err(invalid(
            format!("<{}> (line {})", root.tag_name().name(), line(root)),
            "expected <robot> as the root element of a URDF".into(),
        ));
    }
    for (tag, limit) in [("link", limits::MAX_LINKS), ("joint", limits::MAX_LINKS)] {
        let count = root.children().filter(|n| n.has_tag_name(tag)).count();
        if count > limit {
            return Err(invalid(
                "<robot>".into(),
                format!("has {count} <{tag}> elements; the limit is {limit}"),
            ));
        }
        let mut first_line: HashMap<&str, u32> = HashMap::new();
        for node in root.children().filter(|n| n.has_tag_name(tag)) {
            let Some(name) = node.attribute("name") else {
                return Err(invalid(format!("<{tag}> (line {})", line(node)), "has no name attribute".into()));
            };
            if let Some(first) = first_line.insert(name, line(node)) {
                return Err(invalid(
                    format!("<{tag} name=\"{name}\"> (line {})", line(node)),
                    format!("a second {tag} named `{name}` (the first is at line {first}); names must be unique"),
                ));
            }
        }
    }
    for joint in root.children().filter(|n| n.has_tag_name("joint")) {
        let kind = joint.attribute("type").unwrap_or("");
        if !JOINT_TYPES.contains(&kind) {
            return Err(invalid(
                format!(
                    "<joint name=\"{}\"> (line {}) type",
                    joint.attribute("name").unwrap_or(""),
                    line(joint)
                ),
                format!("`{kind}`: expected one of {}", JOINT_TYPES.join(", ")),
            ));
        }
    }
    for geometry in doc.descendants().filter(|n| n.has_tag_name("geometry")) {
        let shapes: Vec<&str> = geometry
            .children()
            .filter(|n| n.is_element())
            .map(|n| n.tag_name().name())
            .collect();
        if shapes.len() != 1 || !SHAPES.contains(&shapes[0]) {
            return Err(invalid(
                format!(
                    "link `{}` <geometry> (line {})",
                    geometry
                        .ancestors()
                        .find(|n| n.has_tag_name("link"))
                        .and_then(|n| n.attribute("name"))
                        .unwrap_or("?"),
                    line(geometry)
                ),
                format!("holds {shapes:?}: expected exactly one of {}", SHAPES.join(", ")),
            ));
        }
    }
    for node in doc.descendants().filter(|n| n.is_element()) {
        for &(tag, attribute, count, range) in NUMBERS {
            if node.tag_name().name() != tag {
                continue;
            }
            let Some(text) = node.attribute(attribute) else { continue };
            let element = format!("<{tag} {attribute}=\"{text}\"> (line {})", line(node));
            check_numbers(text, count, range).map_err(|message| invalid(element, message))?;
        }
    }
    Ok(())
}

fn check_numbers(text: &str, count: usize, range: Range) -> Result<(), String> {
    let words: Vec<&str> = text.split_whitespace().collect();
    if words.len() != count {
        return Err(format!("expected {count} number(s), found {}", words.len()));
    }
    let (bound, what) = match range {
        Range::Length => (limits::MAX_LENGTH_M, "m"),
        Range::JointLimit => (limits::MAX_JOINT_LIMIT, "rad or m (wider limits: make the joint continuous)"),
        Range::Other => (MAX_OTHER, ""),
    };
    for word in words {
        let value: f64 = word.parse().map_err(|_| format!("`{word}` is not a number"))?;
        if !value.is_finite() {
            return Err(format!("`{word}` is not a finite number"));
        }
        if value.abs() > bound {
            return Err(format!("`{word}`: expected at most {bound} {what} in absolute value").replace("  ", " "));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn error(xml: &str) -> String {
        let doc = roxmltree::Document::parse(xml).expect("well-formed");
        check(&doc, Path::new("r.urdf")).expect_err("refused").to_string()
    }

    #[test]
    fn bad_float_names_element_attribute_and_line() {
        let message = error("<robot name=\"r\">\n<link name=\"a\">\n<inertial><mass value=\"1,5\"/></inertial></link></robot>");
        assert!(
            message.contains("<mass value=\"1,5\"> (line 3)") && message.contains("`1,5` is not a number"),
            "{message}"
        );
    }

    #[test]
    fn huge_joint_limits_are_refused() {
        let message =
            error("<robot name=\"r\"><joint name=\"j\" type=\"revolute\"><limit lower=\"-1e308\" upper=\"1e308\"/></joint></robot>");
        assert!(message.contains("lower=\"-1e308\""), "{message}");
    }

    #[test]
    fn duplicate_link_is_refused_with_both_lines() {
        let message = error("<robot name=\"r\">\n<link name=\"a\"/>\n<link name=\"a\"/></robot>");
        assert!(message.contains("line 3") && message.contains("first is at line 2"), "{message}");
    }
}
