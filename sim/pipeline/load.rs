//! Reading a run's inputs: the robot (design JSON, URDF, MJCF) into one model, and the scenario.

use crate::design;
use crate::error::Error;
use crate::model::{self, Model, UrdfOptions};
use std::path::{Path, PathBuf};

/// How to read the robot a run is about.
#[derive(Debug, Clone, Default)]
pub struct LoadOptions {
    /// URDF: first link of the chain (default: the root).
    pub base_link: Option<String>,
    /// URDF: last link of the chain; MJCF: a body or site holding the tool frame (default: the
    /// arm's tool frame, see [`crate::model::from_urdf`] and [`crate::model::from_mjcf`]).
    pub tip_link: Option<String>,
    /// URDF: roots for `package://` URIs, searched before `ROS_PACKAGE_PATH`.
    pub package_paths: Vec<PathBuf>,
}

/// What kind of robot description a file is, from its extension.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum InputKind {
    /// Design JSON.
    Design,
    /// URDF.
    Urdf,
    /// MJCF (`.xml`, `.mjcf`), loaded through MuJoCo.
    Mjcf,
    /// A Timor assembly (JSON with `moduleSet` and `moduleOrder`).
    Timor,
}

/// The robot files read, for messages.
const ROBOT_FILES: &str =
    "expected a design (.json), a Timor assembly (.json), a URDF (.urdf) or an MJCF (.xml, .mjcf) file, or a catalog id (modular6/D-Ls-Il-D-Is-Ll, preset/UR5e, timor:IMPROV/1,21,4,22,5,23,12)";

/// The Timor module set and module order a Timor assembly id names (`timor:SET/M1,M2,...`), when
/// `path` is no file and its text is one.
fn timor_id(path: &Path) -> Result<Option<(String, Vec<String>)>, Error> {
    if path.exists() {
        return Ok(None);
    }
    let Some(text) = path.to_str() else { return Ok(None) };
    model::parse_timor_id(text).map_err(|reason| Error::UnknownInput {
        path: path.to_path_buf(),
        reason,
    })
}

/// The design a catalog id names, when `path` is no file and its text is one.
fn catalog_design(path: &Path) -> Result<Option<design::Design>, Error> {
    if path.exists() {
        return Ok(None);
    }
    let Some(text) = path.to_str() else { return Ok(None) };
    design::Design::from_catalog_id(text).map_err(|reason| Error::UnknownInput {
        path: path.to_path_buf(),
        reason,
    })
}

/// The kind of a robot description file: from its extension, and for `.xml` and `.mjcf` from
/// its root element (a URDF saved as `.xml` is read as the URDF it is).
///
/// # Errors
/// [`Error::UnknownInput`] for standard input (`-`), a directory, a xacro file, an XML file
/// whose root is neither `<mujoco>` nor `<robot>`, or another extension.
pub fn input_kind(path: &Path) -> Result<InputKind, Error> {
    let unknown = |reason: String| {
        Err(Error::UnknownInput {
            path: path.to_path_buf(),
            reason,
        })
    };
    if path == Path::new("-") {
        return unknown(format!("a robot is not read from standard input: save it to a file; {ROBOT_FILES}"));
    }
    if path.is_dir() {
        return unknown(format!(
            "is a directory; {ROBOT_FILES} (for many designs: validate-design sweep DIR/*.json)"
        ));
    }
    if catalog_design(path)?.is_some() {
        return Ok(InputKind::Design);
    }
    if timor_id(path)?.is_some() {
        return Ok(InputKind::Timor);
    }
    let extension = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
    match extension.as_deref() {
        Some("json") => json_kind(path),
        Some("urdf") => Ok(InputKind::Urdf),
        Some("xml" | "mjcf") => match root_element(path).as_deref() {
            Some("robot") => Ok(InputKind::Urdf),
            // Unreadable or not XML: MuJoCo's loader says what is wrong with it.
            Some("mujoco") | None => Ok(InputKind::Mjcf),
            Some(other) => unknown(format!(
                "the root element is <{other}>, neither MJCF's <mujoco> nor URDF's <robot>; {ROBOT_FILES}"
            )),
        },
        Some("xacro") => unknown(
            "a xacro macro file, not a URDF: expand it first (`xacro FILE > robot.urdf`, ROS's xacro package) and give the URDF".into(),
        ),
        Some(other) => unknown(format!("unknown extension `.{other}`; {ROBOT_FILES}")),
        None => unknown(format!("no extension to tell the input type; {ROBOT_FILES}")),
    }
}

/// A JSON robot file's kind: a design, or a Timor assembly by its keys. A Timor module set is
/// no robot: the error lists its modules and says how to make one.
fn json_kind(path: &Path) -> Result<InputKind, Error> {
    // Unreadable files are the design reader's to report, with its message.
    let Ok(text) = crate::files::read_text(path, crate::limits::MAX_TEXT_BYTES) else {
        return Ok(InputKind::Design);
    };
    match model::timor_kind(&text) {
        Some(model::TimorKind::Assembly) => Ok(InputKind::Timor),
        Some(model::TimorKind::ModuleSet) => {
            let summary = model::load_module_set(path)?;
            let ids: Vec<&str> = summary.modules.iter().map(|(id, _)| id.as_str()).collect();
            Err(Error::UnknownInput {
                path: path.to_path_buf(),
                reason: format!(
                    "a Timor module set ({} modules: {}), not one robot: give an assembly of its modules, a JSON file {{\"moduleSet\": \"{}\", \"moduleOrder\": [\"{}\", ...]}} from the base module on (docs/inputs.md, Timor module sets and assemblies)",
                    ids.len(),
                    ids.join(", "),
                    path.display(),
                    summary.bases.first().map_or("BASE", String::as_str)
                ),
            })
        }
        None => Ok(InputKind::Design),
    }
}

/// The name of an XML file's root element, from its first 64 KiB; `None` where the file cannot be
/// read or the root is not found there.
fn root_element(path: &Path) -> Option<String> {
    use std::io::Read;
    let mut head = Vec::new();
    std::fs::File::open(path).ok()?.take(64 * 1024).read_to_end(&mut head).ok()?;
    let mut reader = quick_xml::Reader::from_reader(head.as_slice());
    let mut buffer = Vec::new();
    loop {
        match reader.read_event_into(&mut buffer).ok()? {
            quick_xml::events::Event::Start(e) | quick_xml::events::Event::Empty(e) => {
                return Some(String::from_utf8_lossy(e.local_name().as_ref()).into_owned());
            }
            quick_xml::events::Event::Eof => return None,
            _ => buffer.clear(),
        }
    }
}

/// A loaded robot: the model, and the design when it came from one.
#[derive(Debug, Clone)]
pub struct Loaded {
    /// The model every stage uses.
    pub model: Model,
    /// The validated design, for design files.
    pub design: Option<design::Design>,
}

/// Reads a design JSON, a URDF or an MJCF file into a model.
///
/// # Errors
/// The design or model stage's error, naming the file and the field or element.
pub fn load(path: &Path, opts: &LoadOptions) -> Result<Loaded, Error> {
    match input_kind(path)? {
        InputKind::Design => {
            let design = match catalog_design(path)? {
                Some(design) => design,
                None => design::load(path)?,
            };
            Ok(Loaded {
                model: model::from_design(&design),
                design: Some(design),
            })
        }
        InputKind::Urdf => {
            let urdf = UrdfOptions {
                base_link: opts.base_link.clone(),
                tip_link: opts.tip_link.clone(),
                package_paths: opts.package_paths.clone(),
            };
            Ok(Loaded {
                model: model::from_urdf(path, &urdf)?,
                design: None,
            })
        }
        InputKind::Timor => {
            // The chain of an assembly runs from its base connector to its free connector.
            if let Some(option) = [(opts.base_link.is_some(), "--base"), (opts.tip_link.is_some(), "--tip")]
                .iter()
                .find_map(|(given, name)| given.then_some(*name))
            {
                return Err(model::ModelError::InvalidValue {
                    path: path.to_path_buf(),
                    element: option.into(),
                    message: "is for URDF and MJCF input; a Timor assembly runs from its base connector to its free (or `eef`) connector"
                        .into(),
                }
                .into());
            }
            let model = match timor_id(path)? {
                Some((set, order)) => model::TimorSet::load(&set)?.assemble(&order, path)?,
                None => model::from_timor(path)?,
            };
            Ok(Loaded { model, design: None })
        }
        InputKind::Mjcf => {
            // The base of an MJCF chain is where its first joint hangs; a URDF-style base link
            // would be silently meaningless.
            if opts.base_link.is_some() {
                return Err(model::ModelError::UnsupportedMjcf {
                    path: path.to_path_buf(),
                    element: "--base".into(),
                    problem: "is for URDF input; an MJCF chain runs from the body holding its first joint".into(),
                }
                .into());
            }
            Ok(Loaded {
                model: model::from_mjcf_to(path, opts.tip_link.as_deref())?,
                design: None,
            })
        }
    }
}

/// Reads a design JSON, a URDF or an MJCF file into a model.
///
/// # Errors
/// As [`load`].
pub fn load_model(path: &Path, opts: &LoadOptions) -> Result<Model, Error> {
    Ok(load(path, opts)?.model)
}

/// Reads and validates a scenario file.
///
/// # Errors
/// [`Error::Scenario`] naming the file and the field.
pub fn load_scenario(path: &Path) -> Result<crate::scenario::Scenario, Error> {
    Ok(crate::scenario::load(path)?)
}

/// Scenario loaded when none is given, relative to the current directory, when it exists there.
pub const DEFAULT_SCENARIO: &str = "scenarios/course.json";

/// The scenario at `path`; with none, [`DEFAULT_SCENARIO`] when that file exists under the
/// current directory, else the same course built in.
///
/// # Errors
/// [`Error::Scenario`] naming the file and the field.
pub fn scenario_or_default(path: Option<&Path>) -> Result<crate::scenario::Scenario, Error> {
    match path {
        Some(path) => load_scenario(path),
        None if Path::new(DEFAULT_SCENARIO).is_file() => load_scenario(Path::new(DEFAULT_SCENARIO)),
        // The committed course is this generator's output, byte for byte (tests/scenario.rs).
        None => Ok(crate::scenario::generate::course(crate::scenario::generate::COURSE_SEED)),
    }
}
