//! The company's manufacturing knowledge as typed data.
//!
//! Knowledge lives in RON files under a knowledge directory (by default the
//! repository's `knowledge/`, also embedded in the binary). Everything is
//! loaded and validated before planning; every problem found is reported
//! with file, line and column, as many as can be found in one run.

// Knowledge errors carry the file text for miette's pointed display; they are
// rare and off the hot path, so their size does not matter.
#![allow(clippy::result_large_err)]

use std::collections::btree_map::Entry;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

pub mod interference;
pub mod load;
pub mod methods;
pub mod posts;
pub mod recognition;
pub mod resources;
pub mod sequencing;
pub mod sizing;
pub mod strategies;

pub use interference::*;
pub use load::{load_ron, parse_ron, KnowledgeError};
pub use methods::*;
pub use posts::PostProcessor;
pub use recognition::*;
pub use resources::*;
pub use sequencing::*;
pub use sizing::*;
pub use strategies::*;

/// All knowledge a plan uses, by id (ordered maps: deterministic).
#[derive(Debug, Clone, PartialEq)]
pub struct Knowledge {
    /// Where it was read from (`builtin:` for the embedded copy).
    pub origin: String,
    pub machines: BTreeMap<String, Machine>,
    pub tool_sets: BTreeMap<String, ToolSet>,
    pub materials: BTreeMap<String, Material>,
    /// Post-processors by id (`posts/`).
    pub posts: BTreeMap<String, PostProcessor>,
    /// Constants of the wall sizing model (`sizing.ron`).
    pub sizing: SizingKnowledge,
    /// Thresholds for recognising walls (`recognition_walls.ron`).
    pub wall_recognition: WallRecognition,
    /// Thresholds for recognising depressions and details
    /// (`recognition_depressions.ron`).
    pub depression_recognition: DepressionRecognition,
    /// Stiffness-feature sequencing rules (`sequencing.ron`).
    pub sequencing: SequencingKnowledge,
    /// Machining-feature determination strategies (`strategies.ron`).
    pub strategies: StrategyKnowledge,
    /// Interference handling and remaining material (`interference.ron`).
    pub interference: InterferenceKnowledge,
    /// Operation methods for the modular tool paths (`methods.ron`).
    pub methods: MethodKnowledge,
}

/// Files at the knowledge root; each is required.
pub const ROOT_FILES: [&str; 7] = [
    SIZING_FILE,
    "recognition_walls.ron",
    "recognition_depressions.ron",
    SEQUENCING_FILE,
    STRATEGIES_FILE,
    INTERFERENCE_FILE,
    METHODS_FILE,
];

/// The embedded copy of the repository's `knowledge/` directory:
/// `(relative path, text)`.
const BUILTIN: &[(&str, &str)] = &[
    (
        "machines/hsm_5axis.ron",
        include_str!("../../../knowledge/machines/hsm_5axis.ron"),
    ),
    (
        "tools/endmills_12_20.ron",
        include_str!("../../../knowledge/tools/endmills_12_20.ron"),
    ),
    (
        "materials/al7075.ron",
        include_str!("../../../knowledge/materials/al7075.ron"),
    ),
    (
        "posts/fanuc.ron",
        include_str!("../../../knowledge/posts/fanuc.ron"),
    ),
    (
        "posts/linuxcnc.ron",
        include_str!("../../../knowledge/posts/linuxcnc.ron"),
    ),
    ("sizing.ron", include_str!("../../../knowledge/sizing.ron")),
    (
        "recognition_walls.ron",
        include_str!("../../../knowledge/recognition_walls.ron"),
    ),
    (
        "recognition_depressions.ron",
        include_str!("../../../knowledge/recognition_depressions.ron"),
    ),
    (
        "sequencing.ron",
        include_str!("../../../knowledge/sequencing.ron"),
    ),
    (
        "strategies.ron",
        include_str!("../../../knowledge/strategies.ron"),
    ),
    (
        "interference.ron",
        include_str!("../../../knowledge/interference.ron"),
    ),
    (
        "methods.ron",
        include_str!("../../../knowledge/methods.ron"),
    ),
];

/// The name of the sizing file at the knowledge root.
pub const SIZING_FILE: &str = "sizing.ron";

/// Default resources when a set-up names none.
pub const DEFAULT_MACHINE: &str = "hsm_5axis";
pub const DEFAULT_TOOL_SET: &str = "endmills_12_20";
pub const DEFAULT_MATERIAL: &str = "al7075";
pub const DEFAULT_POST: &str = "linuxcnc";

/// The folders of one-item-per-file knowledge, by id.
pub const ITEM_FOLDERS: [&str; 4] = ["machines", "tools", "materials", "posts"];

#[derive(Default)]
struct Collector {
    k: Option<Knowledge>,
    errors: Vec<KnowledgeError>,
}

impl Knowledge {
    /// The knowledge embedded in the binary (a copy of `knowledge/`).
    pub fn builtin() -> Result<Knowledge, Vec<KnowledgeError>> {
        let files: Vec<(PathBuf, String)> = BUILTIN
            .iter()
            .map(|(p, t)| {
                (
                    PathBuf::from(format!("builtin:knowledge/{p}")),
                    t.to_string(),
                )
            })
            .collect();
        Self::from_files("builtin:knowledge", &files)
    }

    /// Reads and validates a knowledge directory.
    pub fn load_dir(dir: &Path) -> Result<Knowledge, Vec<KnowledgeError>> {
        let mut files = Vec::new();
        let mut errors = Vec::new();
        for sub in ITEM_FOLDERS {
            let d = dir.join(sub);
            // Posts are needed only for G-code; older directories have none.
            if sub == "posts" && !d.exists() {
                continue;
            }
            match load::ron_files(&d) {
                Ok(list) => {
                    for p in list {
                        match std::fs::read_to_string(&p) {
                            Ok(t) => files.push((p, t)),
                            Err(e) => errors.push(KnowledgeError::Read {
                                path: p,
                                reason: e.to_string(),
                            }),
                        }
                    }
                }
                Err(e) => errors.push(e),
            }
        }
        for name in ROOT_FILES {
            let path = dir.join(name);
            match std::fs::read_to_string(&path) {
                Ok(t) => files.push((path, t)),
                // A missing root file is reported once, by `from_files`.
                Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
                Err(e) => errors.push(KnowledgeError::Read {
                    path,
                    reason: e.to_string(),
                }),
            }
        }
        match Self::from_files(&dir.display().to_string(), &files) {
            Ok(k) if errors.is_empty() => Ok(k),
            Ok(_) => Err(errors),
            Err(mut more) => {
                errors.append(&mut more);
                Err(errors)
            }
        }
    }

    /// Builds knowledge from `(path, text)` pairs: files in `machines/`,
    /// `tools/`, `materials/` and `posts/` by their folder, the [`ROOT_FILES`] by name.
    pub fn from_files(
        origin: &str,
        files: &[(PathBuf, String)],
    ) -> Result<Knowledge, Vec<KnowledgeError>> {
        let mut root: BTreeMap<&str, (&PathBuf, &String)> = BTreeMap::new();
        let mut errors = Vec::new();
        let mut rest = Vec::new();
        for (path, text) in files {
            let parent = path
                .parent()
                .and_then(|p| p.file_name())
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_default();
            let name = path
                .file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_default();
            let root_name = ROOT_FILES.iter().find(|r| **r == name);
            match root_name {
                Some(r) if !ITEM_FOLDERS.contains(&parent.as_str()) => {
                    if root.insert(r, (path, text)).is_some() {
                        errors.push(KnowledgeError::Invalid {
                            path: path.clone(),
                            reason: format!("a second {r}"),
                        });
                    }
                }
                _ => rest.push((path, text, parent)),
            }
        }
        let sizing = parse_root::<SizingKnowledge>(&root, SIZING_FILE, origin, &mut errors);
        let walls = parse_root::<WallRecognition>(&root, ROOT_FILES[1], origin, &mut errors);
        let depressions =
            parse_root::<DepressionRecognition>(&root, ROOT_FILES[2], origin, &mut errors);
        let sequencing =
            parse_root::<SequencingKnowledge>(&root, SEQUENCING_FILE, origin, &mut errors);
        let strategies =
            parse_root::<StrategyKnowledge>(&root, STRATEGIES_FILE, origin, &mut errors);
        let interference =
            parse_root::<InterferenceKnowledge>(&root, INTERFERENCE_FILE, origin, &mut errors);
        let methods = parse_root::<MethodKnowledge>(&root, METHODS_FILE, origin, &mut errors);
        let (
            Some(sizing),
            Some(wall_recognition),
            Some(depression_recognition),
            Some(sequencing),
            Some(strategies),
            Some(interference),
            Some(methods),
        ) = (
            sizing,
            walls,
            depressions,
            sequencing,
            strategies,
            interference,
            methods,
        )
        else {
            return Err(errors);
        };
        let mut c = Collector {
            k: Some(Knowledge {
                origin: origin.to_string(),
                machines: BTreeMap::new(),
                tool_sets: BTreeMap::new(),
                materials: BTreeMap::new(),
                posts: BTreeMap::new(),
                sizing,
                wall_recognition,
                depression_recognition,
                sequencing,
                strategies,
                interference,
                methods,
            }),
            errors,
        };
        for (path, text, parent) in rest {
            match parent.as_str() {
                "machines" => c.add(path, text, |k| &mut k.machines, |m: &Machine| &m.id),
                "tools" => c.add(path, text, |k| &mut k.tool_sets, |t: &ToolSet| &t.id),
                "materials" => c.add(path, text, |k| &mut k.materials, |m: &Material| &m.id),
                "posts" => {
                    // Checked here, not in `validate`, so problems name the file.
                    if let Ok(p) = parse_ron::<PostProcessor>(text, path) {
                        for problem in p.problems() {
                            c.errors.push(KnowledgeError::Invalid {
                                path: path.clone(),
                                reason: problem,
                            });
                        }
                    }
                    c.add(path, text, |k| &mut k.posts, |p: &PostProcessor| &p.id)
                }
                _ => c.errors.push(KnowledgeError::Invalid {
                    path: path.clone(),
                    reason:
                        "not in a known knowledge folder (machines/, tools/, materials/, posts/)"
                            .into(),
                }),
            }
        }
        let k = c.k.take().expect("set above");
        let mut errors = c.errors;
        errors.extend(validate(&k));
        if errors.is_empty() {
            Ok(k)
        } else {
            Err(errors)
        }
    }

    pub fn machine(&self, id: &str) -> Option<&Machine> {
        self.machines.get(id)
    }

    pub fn tool_set(&self, id: &str) -> Option<&ToolSet> {
        self.tool_sets.get(id)
    }

    pub fn material(&self, id: &str) -> Option<&Material> {
        self.materials.get(id)
    }

    pub fn post(&self, id: &str) -> Option<&PostProcessor> {
        self.posts.get(id)
    }
}

/// Parses one required root file, recording a problem when it is missing or bad.
fn parse_root<T: serde::de::DeserializeOwned>(
    root: &BTreeMap<&str, (&PathBuf, &String)>,
    name: &str,
    origin: &str,
    errors: &mut Vec<KnowledgeError>,
) -> Option<T> {
    match root.get(name) {
        Some((path, text)) => match parse_ron::<T>(text, path) {
            Ok(v) => Some(v),
            Err(e) => {
                errors.push(e);
                None
            }
        },
        None => {
            errors.push(KnowledgeError::Invalid {
                path: PathBuf::from(origin).join(name),
                reason: format!("missing {name}: every knowledge directory needs it"),
            });
            None
        }
    }
}

impl Collector {
    fn add<T: serde::de::DeserializeOwned>(
        &mut self,
        path: &Path,
        text: &str,
        map: impl Fn(&mut Knowledge) -> &mut BTreeMap<String, T>,
        id: impl Fn(&T) -> &String,
    ) {
        match parse_ron::<T>(text, path) {
            Ok(item) => {
                let key = id(&item).clone();
                let k = self.k.as_mut().expect("present while collecting");
                match map(k).entry(key) {
                    Entry::Occupied(e) => self.errors.push(KnowledgeError::Invalid {
                        path: path.to_path_buf(),
                        reason: format!(
                            "duplicate id `{}` (already defined by another file)",
                            e.key()
                        ),
                    }),
                    Entry::Vacant(e) => {
                        e.insert(item);
                    }
                }
            }
            Err(e) => self.errors.push(e),
        }
    }
}

fn invalid(what: &str, reason: String) -> KnowledgeError {
    KnowledgeError::Invalid {
        path: PathBuf::from(what),
        reason,
    }
}

/// Checks values a parser cannot: ranges, positivity, references.
fn validate(k: &Knowledge) -> Vec<KnowledgeError> {
    let mut errors = Vec::new();
    let positive = |errors: &mut Vec<KnowledgeError>, what: &str, name: &str, v: f64| {
        if !(v.is_finite() && v > 0.0) {
            errors.push(invalid(
                what,
                format!("`{name}` must be a positive number, not {v}"),
            ));
        }
    };
    for m in k.machines.values() {
        let what = format!("machine `{}`", m.id);
        for (axis, a) in [("x", &m.x), ("y", &m.y), ("z", &m.z)] {
            if a.travel.0.partial_cmp(&a.travel.1) != Some(std::cmp::Ordering::Less) {
                errors.push(invalid(
                    &what,
                    format!(
                        "axis {axis}: travel ({}, {}) is empty",
                        a.travel.0, a.travel.1
                    ),
                ));
            }
            positive(&mut errors, &what, &format!("{axis}.v_max"), a.v_max);
            positive(&mut errors, &what, &format!("{axis}.a_max"), a.a_max);
        }
        positive(&mut errors, &what, "a_centripetal", m.a_centripetal);
        positive(&mut errors, &what, "spindle_max_rpm", m.spindle_max_rpm);
        match m.kinematics {
            Kinematics::ThreeAxis => {}
            Kinematics::ThreePlusTwo { max_tilt_deg }
            | Kinematics::FiveAxisHead { max_tilt_deg } => {
                if !(0.0..=180.0).contains(&max_tilt_deg) {
                    errors.push(invalid(
                        &what,
                        format!("max_tilt_deg {max_tilt_deg} is outside 0..=180"),
                    ));
                }
            }
        }
    }
    for s in k.tool_sets.values() {
        let mut seen = std::collections::BTreeSet::new();
        if s.tools.is_empty() {
            errors.push(invalid(
                &format!("tool set `{}`", s.id),
                "has no tools".into(),
            ));
        }
        for t in &s.tools {
            let what = format!("tool `{}` in set `{}`", t.id, s.id);
            if !seen.insert(t.id.clone()) {
                errors.push(invalid(&what, "duplicate tool id".into()));
            }
            for (n, v) in [
                ("diameter", t.diameter),
                ("flute_length", t.flute_length),
                ("stickout", t.stickout),
                ("shank_diameter", t.shank_diameter),
                ("holder_diameter", t.holder_diameter),
                ("max_slot_depth_ratio", t.max_slot_depth_ratio),
            ] {
                positive(&mut errors, &what, n, v);
            }
            if t.corner_radius < 0.0 || t.corner_radius > t.diameter / 2.0 {
                errors.push(invalid(
                    &what,
                    format!(
                        "corner_radius {} must lie in 0..=diameter/2 ({})",
                        t.corner_radius,
                        t.diameter / 2.0
                    ),
                ));
            }
            if t.flute_length > t.stickout {
                errors.push(invalid(
                    &what,
                    format!(
                        "flute_length {} is longer than the stickout {}",
                        t.flute_length, t.stickout
                    ),
                ));
            }
        }
    }
    for problem in k.sizing.problems() {
        errors.push(invalid("sizing knowledge (sizing.ron)", problem));
    }
    for problem in k.sequencing.problems() {
        errors.push(invalid("sequencing knowledge (sequencing.ron)", problem));
    }
    for problem in k.strategies.problems() {
        errors.push(invalid("strategy knowledge (strategies.ron)", problem));
    }
    for problem in k.interference.problems() {
        errors.push(invalid(
            "interference knowledge (interference.ron)",
            problem,
        ));
    }
    for problem in k.methods.problems() {
        errors.push(invalid("method knowledge (methods.ron)", problem));
    }
    // Rules that name a strategy block must name one that exists.
    for r in &k.interference.keep_order {
        if let FeatureSelector::Block { block, .. } = &r.select {
            let known = k
                .strategies
                .strategies
                .iter()
                .flat_map(|s| s.blocks.iter())
                .any(|b| b.id() == block);
            if !known {
                errors.push(invalid(
                    "interference knowledge (interference.ron)",
                    format!(
                        "keep_order rule `{}` selects block `{block}`, which no strategy in strategies.ron has",
                        r.id
                    ),
                ));
            }
        }
    }
    for m in k.materials.values() {
        let what = format!("material `{}`", m.id);
        positive(&mut errors, &what, "youngs_modulus", m.youngs_modulus);
        positive(&mut errors, &what, "density", m.density);
        positive(&mut errors, &what, "cutting_speed", m.cutting.cutting_speed);
        positive(
            &mut errors,
            &what,
            "feed_per_tooth_roughing",
            m.cutting.feed_per_tooth_roughing,
        );
        positive(
            &mut errors,
            &what,
            "feed_per_tooth_finishing",
            m.cutting.feed_per_tooth_finishing,
        );
    }
    errors
}
