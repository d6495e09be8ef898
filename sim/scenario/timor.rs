//! Timor / CoBRA task files (timor-python 1.1, `task/Task.py`, `Goals.py`, `Obstacle.py`,
//! `Constraints.py`, `utilities/tolerated_pose.py`): read into a [`Scenario`], written back.
//!
//! What a scenario holds is read exactly: obstacles (boxes and cylinders with full lengths,
//! centred; spheres; meshes relative to the task's package folder, the file's folder less the
//! folders of its `ID`), `at` and `reach` goals (their nominal pose, through `frames`), the base
//! (the `basePlacement` nominal), the order of `allGoalsFulfilledInOrder`. A goal's tolerance
//! stays with the goal ([`TaskTolerance`]): IK works within 1 mm and 1 degree, and a goal whose
//! own tolerance is wider is left undecided rather than proven unreachable. Everything else
//! (`returnTo`, `pause` and `follow` goals, `endEffector` velocity limits, another gravity, a
//! tolerance that excludes its own nominal) is named in a warning and not checked.

use super::{Goal, Obstacle, Scenario, ScenarioError, TaskTolerance, Tolerance, TolerancePart};
use crate::model::timor::json::{isometry, quote_non_finite, rows, Id, Matrix4Rows, Num, OneOrMany};
use crate::model::timor::set::{geometry_colliders, GeometryFile};
use crate::model::Shape;
use nalgebra::{Isometry3, Translation3, Vector3};
use serde::Deserialize;
use std::collections::BTreeMap;
use std::path::Path;

/// What a task's mesh files are relative to, for messages.
const PACKAGE: &str = "the task's package folder (its folder less the folders of its ID)";

/// Whether JSON text is a Timor task: an object with `header` and `obstacles`.
pub fn is_timor_task(text: &str) -> bool {
    serde_json::from_str::<serde_json::Value>(&quote_non_finite(text))
        .ok()
        .and_then(|v| v.as_object().map(|o| o.contains_key("header") && o.contains_key("obstacles")))
        .unwrap_or(false)
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct TaskFile {
    header: Header,
    obstacles: Vec<ObstacleFile>,
    #[serde(default)]
    goals: Vec<GoalFile>,
    #[serde(default, alias = "Constraints")]
    constraints: Vec<serde_json::Value>,
    #[serde(default)]
    frames: BTreeMap<String, FrameFile>,
    #[serde(default)]
    #[allow(dead_code)]
    objects: Option<serde::de::IgnoredAny>,
}

#[derive(Debug, Deserialize)]
#[serde(rename_all = "camelCase")]
struct Header {
    #[serde(rename = "ID")]
    id: Id,
    #[serde(default)]
    task_name: Option<String>,
    #[serde(default)]
    gravity: Option<[Num; 3]>,
}

#[derive(Debug, Deserialize)]
struct FrameFile {
    parent: String,
    transformation: Matrix4Rows,
}

#[derive(Debug, Deserialize)]
struct ObstacleFile {
    #[serde(rename = "ID")]
    id: Id,
    #[serde(default)]
    name: Option<String>,
    collision: OneOrMany<GeometryFile>,
}

#[derive(Debug, Deserialize)]
struct GoalFile {
    #[serde(rename = "ID")]
    id: Id,
    #[serde(rename = "type")]
    kind: String,
    #[serde(default, rename = "goalPose", alias = "goalpose")]
    goal_pose: Option<ToleratedPose>,
    #[serde(default)]
    constraints: Vec<serde_json::Value>,
}

#[derive(Debug, Deserialize)]
#[serde(rename_all = "camelCase")]
struct ToleratedPose {
    nominal: Matrix4Rows,
    #[serde(default)]
    nominal_parent: Option<String>,
    #[serde(default)]
    tolerance_projection: Vec<String>,
    #[serde(default)]
    tolerance: Vec<[Num; 2]>,
    #[serde(default, alias = "frame")]
    tolerance_frame: Vec<String>,
}

/// Reads a Timor task file; what it holds that the scenario does not check is in its `notes`.
///
/// # Errors
/// [`ScenarioError`] naming the file and the key: malformed JSON (with the line), unknown keys,
/// poses that are not rigid, unknown geometry types, missing mesh files, no pose goal left.
pub fn load_timor_task(path: &Path) -> Result<Scenario, ScenarioError> {
    let text = crate::files::read_text(path, crate::limits::MAX_TEXT_BYTES).map_err(|source| ScenarioError::Read {
        path: path.to_path_buf(),
        source,
    })?;
    parse_timor_task(&text, path)
}

/// Reads Timor task text; `path` names it and anchors mesh files.
///
/// # Errors
/// As [`load_timor_task`].
pub fn parse_timor_task(text: &str, path: &Path) -> Result<Scenario, ScenarioError> {
    let invalid = |field: String, message: String| ScenarioError::Invalid {
        path: path.to_path_buf(),
        field,
        message,
    };
    let file: TaskFile = serde_json::from_str(&quote_non_finite(text)).map_err(|e| ScenarioError::Parse {
        path: path.to_path_buf(),
        message: format!("a Timor task: {e}"),
    })?;
    let mut warnings = Vec::new();
    let id = file.header.id.0.clone();
    let frames = Frames { frames: &file.frames };

    // Timor's package folder: the file's path less the folders its ID names.
    let folder = path.parent().unwrap_or(Path::new("."));
    let depth = id.split('/').count().saturating_sub(1);
    let package = folder
        .ancestors()
        .nth(depth)
        .filter(|_| folder.ends_with(id.rsplit_once('/').map_or("", |(d, _)| d)))
        .unwrap_or(folder);

    let mut obstacles = Vec::new();
    for (k, obstacle) in file.obstacles.iter().enumerate() {
        let base_name = obstacle
            .name
            .clone()
            .filter(|n| !n.is_empty())
            .unwrap_or_else(|| format!("obstacle {}", obstacle.id));
        let geometries = obstacle.collision_list();
        for (g, geometry) in geometries.iter().enumerate() {
            let name = if geometries.len() > 1 {
                format!("{base_name}/{g}")
            } else {
                base_name.clone()
            };
            let colliders = geometry_colliders(geometry, &format!("obstacles[{k}].collision[{g}]"), package, &name, PACKAGE)
                .map_err(|(field, message)| invalid(field, message))?;
            obstacles.extend(colliders.into_iter().map(|c| Obstacle {
                name: c.label,
                world_from_shape: c.link_from_shape,
                shape: c.shape,
            }));
        }
    }

    let mut world_from_base = Isometry3::identity();
    let mut order: Option<Vec<String>> = None;
    let mut based = false;
    for (k, constraint) in file.constraints.iter().enumerate() {
        let kind = constraint.get("type").and_then(serde_json::Value::as_str).unwrap_or("alwaysTrue");
        match kind {
            "basePlacement" => {
                let pose: ToleratedPose = constraint
                    .get("pose")
                    .cloned()
                    .map(serde_json::from_value)
                    .transpose()
                    .map_err(|e| invalid(format!("constraints[{k}].pose"), e.to_string()))?
                    .ok_or_else(|| invalid(format!("constraints[{k}]"), "a basePlacement needs `pose`".into()))?;
                world_from_base = frames
                    .world_pose(&pose, &format!("constraints[{k}].pose"))
                    .map_err(|(f, m)| invalid(f, m))?;
                based = true;
                // Within a micrometre and a microradian (as written back) the base is fixed.
                let fixed = !pose.tolerance.is_empty() && pose.tolerance.iter().flatten().all(|b| b.0.abs() <= 1e-6);
                if !fixed {
                    warnings.push(if pose.tolerance_projection.is_empty() {
                    "the task leaves the base placement free (basePlacement has no tolerance): the robot stands at its nominal pose, and a verdict is for that placement".to_string()
                } else {
                    format!(
                        "the task lets the base move within {}: the robot stands at the nominal pose, and a verdict is for that placement",
                        tolerance_text(&pose)
                    )
                    });
                }
            }
            "allGoalsFulfilledInOrder" => {
                let listed = constraint.get("order").and_then(serde_json::Value::as_array).map(|ids| {
                    ids.iter()
                        .map(|v| v.as_str().map(str::to_string).unwrap_or_else(|| v.to_string()))
                        .collect::<Vec<_>>()
                });
                order = Some(listed.ok_or_else(|| invalid(format!("constraints[{k}].order"), "expected a list of goal IDs".into()))?);
            }
            // What every run checks anyway: the joint limits, ratings, collisions, every goal.
            "joint" | "selfCollisionFree" | "collisionFree" | "allGoalsFulfilled" | "validAssembly" | "alwaysTrue" => {}
            other => warnings.push(format!("constraints[{k}]: a `{other}` constraint is not checked")),
        }
    }
    if !based {
        warnings.push("the task has no basePlacement: the robot stands at the world origin".into());
    }
    if let Some(g) = &file.header.gravity {
        let gravity = Vector3::new(g[0].0, g[1].0, g[2].0);
        if (gravity - Vector3::new(0.0, 0.0, -9.81)).norm() > 1e-9 {
            warnings.push(format!(
                "header.gravity {:?} is not checked: the engines and the static load use -9.81 m/s^2 along z",
                [g[0].0, g[1].0, g[2].0]
            ));
        }
    }

    let mut goals: Vec<(String, Goal)> = Vec::new();
    for (k, goal) in file.goals.iter().enumerate() {
        let field = format!("goals[{k}]");
        match goal.kind.as_str() {
            "at" | "At" | "reach" | "Reach" => {}
            other => {
                warnings.push(format!(
                    "{field} (`{}`): a `{other}` goal is not checked; a scenario's goals are poses",
                    goal.id
                ));
                continue;
            }
        }
        if !goal.constraints.is_empty() {
            warnings.push(format!(
                "{field} (`{}`): its {} goal constraints are not checked",
                goal.id,
                goal.constraints.len()
            ));
        }
        let pose = goal
            .goal_pose
            .as_ref()
            .ok_or_else(|| invalid(format!("{field}.goalPose"), "an `at` or `reach` goal needs goalPose".into()))?;
        let world = frames
            .world_pose(pose, &format!("{field}.goalPose"))
            .map_err(|(f, m)| invalid(f, m))?;
        let (tolerance, task) = match goal_tolerance(pose, &format!("{field}.goalPose")).map_err(|(f, m)| invalid(f, m))? {
            Ok(judged) => judged,
            Err(why) => {
                warnings.push(format!("{field} (`{}`): not checked: {why}", goal.id));
                continue;
            }
        };
        goals.push((
            goal.id.0.clone(),
            Goal {
                name: goal.id.0.clone(),
                position: world.translation.vector,
                rotation: world.rotation,
                tolerance,
                task: Some(task),
            },
        ));
    }
    if let Some(order) = order {
        let mut ordered = Vec::with_capacity(goals.len());
        for id in &order {
            if let Some(at) = goals.iter().position(|(g, _)| g == id) {
                ordered.push(goals.remove(at));
            }
        }
        ordered.append(&mut goals);
        goals = ordered;
    }
    if goals.is_empty() {
        let skipped: Vec<&String> = warnings.iter().filter(|w| w.starts_with("goals[")).collect();
        return Err(invalid(
            "goals".into(),
            format!(
                "holds no `at` or `reach` goal proving-ground can check; a scenario needs at least one pose goal{}{}",
                if skipped.is_empty() { "" } else { ": " },
                skipped.iter().map(|s| s.as_str()).collect::<Vec<_>>().join("; ")
            ),
        ));
    }
    let name = file
        .header
        .task_name
        .clone()
        .filter(|n| !n.is_empty())
        .unwrap_or(id.clone())
        .replace('/', "_");
    Ok(Scenario {
        name,
        world_from_base,
        floor: None,
        obstacles,
        goals: goals.into_iter().map(|(_, g)| g).collect(),
        home: None,
        provenance: None,
        notes: warnings,
    })
}

impl ObstacleFile {
    fn collision_list(&self) -> Vec<&GeometryFile> {
        match &self.collision {
            OneOrMany::One(g) => vec![g],
            OneOrMany::Many(list) => list.iter().collect(),
        }
    }
}

/// The task's named frames.
struct Frames<'a> {
    frames: &'a BTreeMap<String, FrameFile>,
}

impl Frames<'_> {
    /// The world pose of frame `name`.
    fn world_from(&self, name: &str, field: &str) -> Result<Isometry3<f64>, (String, String)> {
        let mut pose = Isometry3::identity();
        let mut current = name.to_string();
        for _ in 0..=self.frames.len() {
            if current == "world" {
                return Ok(pose);
            }
            let frame = self.frames.get(&current).ok_or_else(|| {
                (
                    field.to_string(),
                    if self.frames.is_empty() {
                        format!("frame `{current}`: the task has no `frames`; expected `world` or a frame it names")
                    } else {
                        format!(
                            "frame `{current}` is not in `frames` (frames: {})",
                            self.frames.keys().cloned().collect::<Vec<_>>().join(", ")
                        )
                    },
                )
            })?;
            pose = isometry(&frame.transformation).map_err(|m| (format!("frames.{current}.transformation"), m))? * pose;
            current = frame.parent.clone();
        }
        Err((field.to_string(), format!("the frames above `{name}` form a loop")))
    }

    fn world_pose(&self, pose: &ToleratedPose, field: &str) -> Result<Isometry3<f64>, (String, String)> {
        let nominal = isometry(&pose.nominal).map_err(|m| (format!("{field}.nominal"), m))?;
        let parent = pose.nominal_parent.as_deref().unwrap_or("world");
        Ok(self.world_from(parent, &format!("{field}.nominalParent"))? * nominal)
    }
}

fn tolerance_text(pose: &ToleratedPose) -> String {
    parts(pose).map(|parts| super::parts_text(&parts)).unwrap_or_default()
}

fn parts(pose: &ToleratedPose) -> Result<Vec<TolerancePart>, String> {
    if pose.tolerance.len() != pose.tolerance_projection.len() {
        return Err(format!(
            "toleranceProjection has {} entries and tolerance {}; expected one interval per projection",
            pose.tolerance_projection.len(),
            pose.tolerance.len()
        ));
    }
    Ok(pose
        .tolerance_projection
        .iter()
        .zip(&pose.tolerance)
        .enumerate()
        .map(|(k, (projection, interval))| TolerancePart {
            projection: projection.clone(),
            interval: [interval[0].0, interval[1].0],
            frame: pose.tolerance_frame.get(k).cloned().unwrap_or_else(|| "nominal".into()),
        })
        .collect())
}

/// How a goal's tolerance is judged: the scenario's mode and the balls inside and around the
/// task's region; `Err` inside `Ok` for a tolerance the harness cannot judge (said in a warning).
type Judged = Result<(Tolerance, TaskTolerance), String>;

fn goal_tolerance(pose: &ToleratedPose, field: &str) -> Result<Judged, (String, String)> {
    let parts = parts(pose).map_err(|m| (field.to_string(), m))?;
    if parts.is_empty() {
        return Ok(Err("its goalPose has no tolerance, which Timor reads as any pose at all".into()));
    }
    // Inner and outer radii per kind (position m, rotation rad), intersected over the parts.
    let (mut inner, mut outer) = ([f64::INFINITY; 2], [f64::INFINITY; 2]);
    let mut axes: [[Option<(f64, f64)>; 3]; 2] = [[None; 3]; 2];
    let mut cylinder: Option<f64> = None;
    for part in &parts {
        let [lo, hi] = part.interval;
        if lo.is_nan() || hi.is_nan() || lo > hi {
            return Err((
                field.to_string(),
                format!("{} interval [{lo}, {hi}]: expected lower <= upper", part.projection),
            ));
        }
        let excludes_nominal = !(lo <= 0.0 && 0.0 <= hi);
        if excludes_nominal {
            return Ok(Err(format!(
                "its tolerance {} [{lo}, {hi}] excludes the nominal pose itself",
                part.projection
            )));
        }
        match part.projection.as_str() {
            "r_sph" => {
                inner[0] = inner[0].min(hi);
                outer[0] = outer[0].min(hi);
            }
            "Theta_R" => {
                inner[1] = inner[1].min(hi);
                outer[1] = outer[1].min(hi);
            }
            "r_cyl" => cylinder = Some(cylinder.map_or(hi, |c| c.min(hi))),
            "x" | "y" | "z" | "N_x" | "N_y" | "N_z" => {
                let kind = usize::from(part.projection.starts_with('N'));
                let axis = (part.projection.as_bytes()[part.projection.len() - 1] - b'x') as usize;
                let previous = axes[kind][axis].unwrap_or((f64::NEG_INFINITY, f64::INFINITY));
                axes[kind][axis] = Some((previous.0.max(lo), previous.1.min(hi)));
            }
            other => {
                return Ok(Err(format!(
                    "its tolerance projection `{other}` is not supported (supported: x, y, z, r_cyl, r_sph, N_x, N_y, N_z, Theta_R)"
                )))
            }
        }
    }
    for kind in 0..2 {
        if axes[kind].iter().any(Option::is_some) {
            let reach = |a: &Option<(f64, f64)>| a.map_or(f64::INFINITY, |(lo, hi)| (-lo).min(hi));
            let far = |a: &Option<(f64, f64)>| a.map_or(f64::INFINITY, |(lo, hi)| (-lo).max(hi));
            let box_inner = axes[kind].iter().map(reach).fold(f64::INFINITY, f64::min);
            let box_outer = axes[kind].iter().map(far).map(|v| v * v).sum::<f64>().sqrt();
            inner[kind] = inner[kind].min(box_inner);
            outer[kind] = outer[kind].min(box_outer);
        }
    }
    if let Some(radius) = cylinder {
        // A cylinder about the nominal z axis, cut by the z interval if any.
        let z = axes[0][2];
        let height_in = z.map_or(f64::INFINITY, |(lo, hi)| (-lo).min(hi));
        let height_out = z.map_or(f64::INFINITY, |(lo, hi)| (-lo).max(hi));
        inner[0] = inner[0].min(radius.min(height_in));
        outer[0] = outer[0].min(radius.hypot(height_out));
    }
    if !inner[0].is_finite() {
        return Ok(Err(
            "its tolerance leaves the position free; proving-ground judges position goals, position and orientation goals".into(),
        ));
    }
    // A rotation is never more than pi from another.
    outer[1] = outer[1].min(std::f64::consts::PI);
    let tolerance = if inner[1] >= std::f64::consts::PI {
        Tolerance::Position
    } else {
        Tolerance::Pose
    };
    Ok(Ok((
        tolerance,
        TaskTolerance {
            parts,
            inner_m: inner[0],
            inner_rad: inner[1],
            outer_m: outer[0],
            outer_rad: outer[1],
        },
    )))
}

/// `scenario` as a Timor task: obstacles as primitives (a capsule as a cylinder and two spheres,
/// the floor as a 100 m square slab 1 m thick under its surface), every goal a `reach` goal with
/// its task tolerance or the harness's (`r_sph` 1 mm, `Theta_R` 1 degree; `z_symmetric` as
/// `N_x` and `N_y` within 1 degree), in course order, the base a `basePlacement` held within
/// 1 um and 1 urad. Mesh files are named relative to `folder` (the task's package folder) where
/// given, else as the scenario names them.
pub fn to_timor_task(scenario: &Scenario, folder: Option<&Path>) -> String {
    let pose = |p: &Isometry3<f64>| serde_json::json!(rows(p));
    let geometry = |kind: &str, parameters: serde_json::Value, p: &Isometry3<f64>| serde_json::json!({"type": kind, "parameters": parameters, "pose": pose(p)});
    let mut obstacles: Vec<serde_json::Value> = Vec::new();
    for (k, obstacle) in scenario.obstacles.iter().enumerate() {
        let at = &obstacle.world_from_shape;
        let collision: Vec<serde_json::Value> = match &obstacle.shape {
            Shape::Box { half_extents } => vec![geometry(
                "box",
                serde_json::json!({"x": 2.0 * half_extents[0], "y": 2.0 * half_extents[1], "z": 2.0 * half_extents[2]}),
                at,
            )],
            Shape::Cylinder { radius, length } => vec![geometry("cylinder", serde_json::json!({"r": radius, "z": length}), at)],
            Shape::Sphere { radius } => vec![geometry("sphere", serde_json::json!({"r": radius}), at)],
            Shape::Capsule { radius, length } => {
                let end = |sign: f64| at * Translation3::new(0.0, 0.0, sign * length / 2.0);
                vec![
                    geometry("cylinder", serde_json::json!({"r": radius, "z": length}), at),
                    geometry("sphere", serde_json::json!({"r": radius}), &end(1.0)),
                    geometry("sphere", serde_json::json!({"r": radius}), &end(-1.0)),
                ]
            }
            Shape::Mesh(mesh) => {
                let file = folder
                    .and_then(|f| {
                        Some(
                            pathdiff::diff_paths(std::path::absolute(&mesh.file).ok()?, std::path::absolute(f).ok()?)?
                                .to_string_lossy()
                                .into_owned(),
                        )
                    })
                    .unwrap_or_else(|| mesh.uri.clone());
                vec![geometry("mesh", serde_json::json!({"file": file, "scale": mesh.scale}), at)]
            }
        };
        obstacles.push(serde_json::json!({"ID": format!("{k}"), "name": obstacle.name, "collision": collision}));
    }
    if let Some(floor) = &scenario.floor {
        let slab = Isometry3::translation(0.0, 0.0, floor.height - 0.5);
        obstacles.push(serde_json::json!({"ID": "floor", "name": "floor", "collision": [geometry("box", serde_json::json!({"x": 100.0, "y": 100.0, "z": 1.0}), &slab)]}));
    }
    let one_degree = std::f64::consts::PI / 180.0;
    let goals: Vec<serde_json::Value> = scenario
        .goals
        .iter()
        .enumerate()
        .map(|(k, goal)| {
            let parts: Vec<(String, [f64; 2], String)> = match &goal.task {
                Some(task) => task
                    .parts
                    .iter()
                    .map(|p| (p.projection.clone(), p.interval, p.frame.clone()))
                    .collect(),
                None => {
                    let mut parts = vec![("r_sph".to_string(), [0.0, 1e-3], "nominal".to_string())];
                    match goal.tolerance {
                        Tolerance::Pose => parts.push(("Theta_R".into(), [0.0, one_degree], "nominal".into())),
                        Tolerance::ZSymmetric => {
                            parts.push(("N_x".into(), [-one_degree, one_degree], "nominal".into()));
                            parts.push(("N_y".into(), [-one_degree, one_degree], "nominal".into()));
                        }
                        Tolerance::Position => {}
                    }
                    parts
                }
            };
            let nominal = Isometry3::from_parts(Translation3::from(goal.position), goal.rotation);
            serde_json::json!({
                "ID": goal_id(scenario, k),
                "type": "reach",
                "goalPose": {
                    "nominal": pose(&nominal),
                    "toleranceProjection": parts.iter().map(|p| p.0.clone()).collect::<Vec<_>>(),
                    "tolerance": parts.iter().map(|p| p.1).collect::<Vec<_>>(),
                    "toleranceFrame": parts.iter().map(|p| p.2.clone()).collect::<Vec<_>>(),
                }
            })
        })
        .collect();
    let order: Vec<String> = (0..scenario.goals.len()).map(|k| goal_id(scenario, k)).collect();
    let task = serde_json::json!({
        "header": {"ID": scenario.name, "version": "2022", "taskName": scenario.name, "tags": ["proving-ground"], "timeStepSize": 0.01, "gravity": [0.0, 0.0, -9.81]},
        "obstacles": obstacles,
        "constraints": [
            {"type": "joint", "parts": ["q", "tau"]},
            {"type": "selfCollisionFree"},
            {"type": "collisionFree"},
            {"type": "allGoalsFulfilledInOrder", "order": order},
            {"type": "basePlacement", "pose": {
                "nominal": pose(&scenario.world_from_base),
                "toleranceProjection": ["r_sph", "Theta_R"],
                "tolerance": [[0.0, 1e-6], [0.0, 1e-6]],
            }},
        ],
        "goals": goals,
    });
    // Only finite numbers and string keys: serde_json refuses nothing here.
    crate::json::to_text(&task).unwrap_or_default()
}

/// Writes [`to_timor_task`] of `scenario` to `path` (mesh files named relative to its folder);
/// an existing file is replaced only when `overwrite` is true.
///
/// # Errors
/// [`ScenarioError::Write`] when the file exists (and `overwrite` is false), is an input of this
/// run, or cannot be written.
pub fn save_timor_task(scenario: &Scenario, path: &Path, overwrite: bool) -> Result<(), ScenarioError> {
    let folder = path.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
    super::write::write_file(path, to_timor_task(scenario, Some(folder)).as_bytes(), overwrite)
}

/// A goal's ID in a written task: its name where no other goal has it, else `index: name`.
fn goal_id(scenario: &Scenario, index: usize) -> String {
    let name = &scenario.goals[index].name;
    if scenario.goals.iter().filter(|g| &g.name == name).count() == 1 {
        name.clone()
    } else {
        format!("{index}: {name}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pose_with(projections: &[(&str, [f64; 2])]) -> ToleratedPose {
        ToleratedPose {
            nominal: std::array::from_fn(|r| std::array::from_fn(|c| Num(if r == c { 1.0 } else { 0.0 }))),
            nominal_parent: None,
            tolerance_projection: projections.iter().map(|p| p.0.to_string()).collect(),
            tolerance: projections.iter().map(|p| [Num(p.1[0]), Num(p.1[1])]).collect(),
            tolerance_frame: vec![],
        }
    }

    #[test]
    fn tolerances_become_the_balls_inside_and_around_them() {
        let judged = |p: &[(&str, [f64; 2])]| goal_tolerance(&pose_with(p), "g").expect("valid");
        let (mode, task) = judged(&[("r_sph", [0.0, 0.01]), ("Theta_R", [0.0, 0.1])]).expect("judged");
        assert_eq!(mode, Tolerance::Pose);
        assert_eq!([task.inner_m, task.outer_m, task.inner_rad, task.outer_rad], [0.01, 0.01, 0.1, 0.1]);
        let (mode, task) = judged(&[("x", [-0.003, 0.004]), ("y", [-0.002, 0.002]), ("z", [-0.001, 0.001])]).expect("box");
        assert_eq!(mode, Tolerance::Position);
        assert_eq!(task.inner_m, 0.001);
        assert!((task.outer_m - (0.004f64.powi(2) + 0.002f64.powi(2) + 0.001f64.powi(2)).sqrt()).abs() < 1e-15);
        let (_, task) = judged(&[("r_cyl", [0.0, 0.003]), ("z", [-0.004, 0.004])]).expect("cylinder");
        assert_eq!([task.inner_m, task.outer_m], [0.003, 0.005]);
        assert!(judged(&[("N_z", [0.999, 1.0]), ("r_sph", [0.0, 0.01])])
            .expect_err("offset")
            .contains("excludes the nominal"));
        assert!(judged(&[("phi_cyl", [-0.1, 0.1])])
            .expect_err("unsupported")
            .contains("not supported"));
        assert!(judged(&[("Theta_R", [0.0, 0.1])])
            .expect_err("free position")
            .contains("position free"));
        assert!(judged(&[]).expect_err("none").contains("any pose"));
    }

    #[test]
    fn a_proof_carries_over_only_to_a_tolerance_inside_the_harnesss() {
        let (_, wide) = goal_tolerance(&pose_with(&[("r_sph", [0.0, 0.01]), ("Theta_R", [0.0, 0.1])]), "g")
            .expect("valid")
            .expect("judged");
        let gap = wide.proof_gap(1e-3, std::f64::consts::PI / 180.0, true).expect("wider");
        assert!(gap.contains("r_sph [0, 0.01]") && gap.contains("10.0 mm"), "{gap}");
        let (_, narrow) = goal_tolerance(&pose_with(&[("r_sph", [0.0, 0.0005]), ("Theta_R", [0.0, 0.01])]), "g")
            .expect("valid")
            .expect("judged");
        assert!(narrow.proof_gap(1e-3, std::f64::consts::PI / 180.0, true).is_none());
        assert!(narrow.accepts(0.0004, 0.005, true) && !narrow.accepts(0.0006, 0.0, true));
    }
}
