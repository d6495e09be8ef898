//! Which pairs a world checks, and which it leaves out and why.

use super::{Body, CollideError, CollideOptions};
use crate::model::Model;
use crate::scenario::Scenario;
use serde::{Deserialize, Serialize};

/// Name of the floor in pair lists.
pub(super) const FLOOR_NAME: &str = "floor";

/// A pair of bodies a [`CollisionWorld`](super::CollisionWorld) checks.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CheckedPair {
    /// Body `a`, always a link.
    pub a: Body,
    /// Body `b`: a link with a larger index, an obstacle or the floor.
    pub b: Body,
    /// Name of body `a` (the link name).
    pub a_name: String,
    /// Name of body `b` (link name, obstacle name, or `floor`).
    pub b_name: String,
}

/// A pair of bodies that is not checked, by name, with the reason. Also the input type of
/// [`CollideOptions::excluded_pairs`], where both names are link names.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct ExcludedPair {
    /// Name of one body.
    pub a: String,
    /// Name of the other body.
    pub b: String,
    /// Why the pair is safe to leave out (several reasons are joined by `; `).
    pub reason: String,
}

impl ExcludedPair {
    /// An exclusion of the pair `a`, `b` for `reason`.
    pub fn new(a: impl Into<String>, b: impl Into<String>, reason: impl Into<String>) -> Self {
        Self {
            a: a.into(),
            b: b.into(),
            reason: reason.into(),
        }
    }
}

/// Two shapes of a checked link pair that are not measured against each other, with the reason:
/// the pieces that overlap by construction (a joint housing and the tube of the link two joints
/// on), while every other shape pair of the two links is still checked.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct ExcludedShapePair {
    /// Name of the first link.
    pub a: String,
    /// Index of its collider in `Link::colliders`.
    pub a_shape: usize,
    /// The collider's label (e.g. `joint module 3`).
    pub a_label: String,
    /// Name of the second link.
    pub b: String,
    /// Index of its collider in `Link::colliders`.
    pub b_shape: usize,
    /// The collider's label.
    pub b_label: String,
    /// Why the shape pair is safe to leave out.
    pub reason: String,
}

/// Two links that overlap by construction (some of their shape pairs are in contact at every
/// configuration), whose other shape pairs are checked but count as in contact only deeper than
/// that overlap: the depth the slabs around two joints 0.1 m apart share with 0.12 m tubes is no
/// fold, anything deeper is.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StructuralAllowance {
    /// Name of the first link.
    pub a: String,
    /// Name of the second link.
    pub b: String,
    /// The deepest overlap of their always-touching shape pairs over the samples (m).
    pub depth_m: f64,
    /// Why.
    pub reason: String,
}

/// Both lists of a world.
#[derive(Debug, Clone, Default)]
pub(super) struct PairLists {
    pub(super) checked: Vec<CheckedPair>,
    pub(super) excluded: Vec<ExcludedPair>,
}

impl PairLists {
    /// Files the pair as excluded when there is a reason, as checked otherwise.
    fn add(&mut self, (a, a_name): (Body, &str), (b, b_name): (Body, &str), reasons: &[String]) {
        if reasons.is_empty() {
            self.checked.push(CheckedPair {
                a,
                b,
                a_name: a_name.into(),
                b_name: b_name.into(),
            });
        } else {
            self.excluded.push(ExcludedPair::new(a_name, b_name, reasons.join("; ")));
        }
    }
}

/// The checked and excluded pairs of a model in a scenario (the rule is in the module docs).
///
/// Order: link pairs `(i, j)`, `i < j`, lexicographic; then each link against each obstacle; then
/// each link against the floor.
///
/// # Errors
/// [`CollideError::UnknownLink`], [`CollideError::MergedLink`] or [`CollideError::SameLink`] for a
/// bad entry of `opts.excluded_pairs`.
pub(super) fn pair_lists(model: &Model, scenario: &Scenario, opts: &CollideOptions) -> Result<PairLists, CollideError> {
    let user = user_exclusions(model, opts)?;
    let no_geometry: Vec<Option<String>> = model
        .links
        .iter()
        .map(|link| {
            (link.colliders.is_empty() && link.segments.is_empty()).then(|| format!("link `{}` has no collision geometry", link.name))
        })
        .collect();
    let link = |i: usize| (Body::Link(i), model.links[i].name.as_str());

    let mut lists = PairLists::default();
    for i in 0..model.links.len() {
        for j in i + 1..model.links.len() {
            let mut reasons = Vec::new();
            if j == i + 1 {
                reasons.push(format!("joined by joint `{}`", model.joints[i].name));
            }
            reasons.extend(user.iter().filter(|(pair, _)| *pair == (i, j)).map(|(_, reason)| reason.clone()));
            reasons.extend(no_geometry[i].iter().chain(&no_geometry[j]).cloned());
            lists.add(link(i), link(j), &reasons);
        }
    }
    for (i, missing) in no_geometry.iter().enumerate() {
        for (k, obstacle) in scenario.obstacles.iter().enumerate() {
            let reasons: Vec<String> = missing.iter().cloned().collect();
            lists.add(link(i), (Body::Obstacle(k), &obstacle.name), &reasons);
        }
    }
    if scenario.floor.is_some() {
        for (i, missing) in no_geometry.iter().enumerate() {
            let mut reasons = Vec::new();
            if i == 0 {
                reasons.push("the base is fixed to the world and mounted on the floor".to_string());
            }
            reasons.extend(missing.iter().cloned());
            lists.add(link(i), (Body::Floor, FLOOR_NAME), &reasons);
        }
    }
    Ok(lists)
}

/// A link pair `(i, j)`, `i < j`, and why it is excluded.
type Exclusion = ((usize, usize), String);

/// The user's exclusions as link index pairs with their reasons.
fn user_exclusions(model: &Model, opts: &CollideOptions) -> Result<Vec<Exclusion>, CollideError> {
    let known = || model.links.iter().map(|l| format!("`{}`", l.name)).collect::<Vec<_>>().join(", ");
    let mut resolved = Vec::with_capacity(opts.excluded_pairs.len());
    for (index, exclusion) in opts.excluded_pairs.iter().enumerate() {
        let find = |name: &str| {
            if let Some(i) = model.links.iter().position(|l| l.name == name) {
                return Ok(i);
            }
            match model.links.iter().find(|l| l.merged.iter().any(|m| m == name)) {
                Some(holder) => Err(CollideError::MergedLink {
                    index,
                    a: exclusion.a.clone(),
                    b: exclusion.b.clone(),
                    link: name.into(),
                    merged_into: holder.name.clone(),
                    known: known(),
                }),
                None => Err(CollideError::UnknownLink {
                    index,
                    a: exclusion.a.clone(),
                    b: exclusion.b.clone(),
                    link: name.into(),
                    model: model.name.clone(),
                    known: known(),
                }),
            }
        };
        let (i, j) = (find(&exclusion.a)?, find(&exclusion.b)?);
        if i == j {
            return Err(CollideError::SameLink {
                index,
                link: exclusion.a.clone(),
            });
        }
        resolved.push(((i.min(j), i.max(j)), exclusion.reason.clone()));
    }
    Ok(resolved)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::{Collider, Link, Segment, Shape};
    use crate::scenario::{Floor, Obstacle};
    use nalgebra::{Isometry3, Vector3};

    fn model() -> Model {
        let text = r#"{"mode": "free", "joints": [{"d": 0.3, "a": 0, "alpha": 1.5}, {"d": 0, "a": 0.4, "alpha": 0},
            {"d": 0, "a": 0.3, "alpha": 0}]}"#;
        let design = crate::design::parse(text, std::path::Path::new("t.json")).expect("valid design");
        crate::model::from_design(&design)
    }

    fn scenario(floor: bool) -> Scenario {
        Scenario {
            name: "s".into(),
            world_from_base: Isometry3::identity(),
            floor: floor.then_some(Floor { height: 0.0 }),
            obstacles: vec![Obstacle {
                name: "ball".into(),
                world_from_shape: Isometry3::translation(0.5, 0.0, 0.5),
                shape: Shape::Sphere { radius: 0.1 },
            }],
            goals: vec![],
            home: None,
            provenance: None,
            notes: Vec::new(),
        }
    }

    #[test]
    fn adjacent_links_and_geometry_less_base_are_excluded_with_reasons() {
        let lists = pair_lists(&model(), &scenario(true), &CollideOptions::default()).expect("valid");
        let names: Vec<(&str, &str)> = lists.checked.iter().map(|p| (p.a_name.as_str(), p.b_name.as_str())).collect();
        assert_eq!(
            names,
            [
                ("link1", "link3"),
                ("link1", "ball"),
                ("link2", "ball"),
                ("link3", "ball"),
                ("link1", "floor"),
                ("link2", "floor"),
                ("link3", "floor")
            ]
        );
        let find = |a: &str, b: &str| lists.excluded.iter().find(|e| e.a == a && e.b == b).expect("listed");
        assert_eq!(find("link1", "link2").reason, "joined by joint `joint2`");
        assert_eq!(
            find("base", "link1").reason,
            "joined by joint `joint1`; link `base` has no collision geometry"
        );
        assert_eq!(find("base", "link2").reason, "link `base` has no collision geometry");
        assert!(find("base", "floor").reason.starts_with("the base is fixed to the world"));
        assert_eq!(lists.checked.len() + lists.excluded.len(), 6 + 4 + 4);
    }

    #[test]
    fn base_with_geometry_is_checked_against_obstacles_and_far_links() {
        let mut model = model();
        model.links[0].colliders.push(Collider {
            link_from_shape: Isometry3::identity(),
            shape: Shape::Sphere { radius: 0.1 },
            label: "base".into(),
        });
        model.links[0].segments.push(Segment {
            start: Vector3::zeros(),
            end: Vector3::zeros(),
        });
        let lists = pair_lists(&model, &scenario(false), &CollideOptions::default()).expect("valid");
        let checked = |a: &str, b: &str| lists.checked.iter().any(|p| p.a_name == a && p.b_name == b);
        assert!(checked("base", "ball") && checked("base", "link2") && checked("base", "link3"));
        assert!(!checked("base", "link1"));
    }

    #[test]
    fn user_exclusions_are_listed_and_bad_names_are_errors() {
        let mut model = model();
        let opts = CollideOptions {
            excluded_pairs: vec![ExcludedPair::new("link3", "link1", "never in contact (SRDF)")],
            ..Default::default()
        };
        let lists = pair_lists(&model, &scenario(false), &opts).expect("valid");
        assert!(lists.checked.iter().all(|p| !(p.a_name == "link1" && p.b_name == "link3")));
        assert!(lists
            .excluded
            .contains(&ExcludedPair::new("link1", "link3", "never in contact (SRDF)")));

        let opts = CollideOptions {
            excluded_pairs: vec![ExcludedPair::new("link1", "lnk3", "typo")],
            ..Default::default()
        };
        let error = pair_lists(&model, &scenario(false), &opts).expect_err("unknown link");
        assert!(error.to_string().contains("no link named `lnk3`"), "{error}");
        assert!(error.to_string().contains("`link3`"), "{error}");

        model.links[3].merged.push("gripper".into());
        let opts = CollideOptions {
            excluded_pairs: vec![ExcludedPair::new("gripper", "link1", "x")],
            ..Default::default()
        };
        let error = pair_lists(&model, &scenario(false), &opts).expect_err("merged link");
        assert!(error.to_string().contains("merged into model link `link3`"), "{error}");

        let opts = CollideOptions {
            excluded_pairs: vec![ExcludedPair::new("link2", "link2", "x")],
            ..Default::default()
        };
        assert!(matches!(
            pair_lists(&model, &scenario(false), &opts),
            Err(CollideError::SameLink { index: 0, .. })
        ));
    }

    #[test]
    fn a_link_without_any_geometry_is_excluded_everywhere() {
        let mut model = model();
        model.links[2] = Link {
            colliders: vec![],
            segments: vec![],
            ..model.links[2].clone()
        };
        let lists = pair_lists(&model, &scenario(true), &CollideOptions::default()).expect("valid");
        assert!(lists.checked.iter().all(|p| p.a_name != "link2" && p.b_name != "link2"));
        assert!(lists.excluded.iter().any(|e| e.a == "link2" && e.b == "ball"));
    }
}
