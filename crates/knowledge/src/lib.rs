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

pub mod check;
pub mod interference;
pub mod load;
pub mod methods;
pub mod posts;
pub mod recognition;
pub mod resources;
pub mod sequencing;
pub mod sizing;
pub mod strategies;
pub mod verification;

pub use check::{Problem, Range, Seg};
pub use interference::*;
pub use load::{load_ron, parse_ron, KnowledgeError};
pub use methods::*;
pub use posts::PostProcessor;
pub use recognition::*;
pub use resources::*;
pub use sequencing::*;
pub use sizing::*;
pub use strategies::*;
pub use verification::*;

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
    /// Stage 9's replay and verdict thresholds (`verification.ron`).
    pub verification: VerificationKnowledge,
}

/// Files at the knowledge root; each is required.
pub const ROOT_FILES: [&str; 8] = [
    SIZING_FILE,
    "recognition_walls.ron",
    "recognition_depressions.ron",
    SEQUENCING_FILE,
    STRATEGIES_FILE,
    INTERFERENCE_FILE,
    METHODS_FILE,
    VERIFICATION_FILE,
];

/// The embedded copy of the repository's `knowledge/` directory:
/// `(relative path, text)`.
const BUILTIN: &[(&str, &str)] = &[
    (
        "machines/hsm_5axis.ron",
        include_str!("../../../knowledge/machines/hsm_5axis.ron"),
    ),
    (
        "tools/alu_hsm.ron",
        include_str!("../../../knowledge/tools/alu_hsm.ron"),
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
    (
        "verification.ron",
        include_str!("../../../knowledge/verification.ron"),
    ),
];

/// The name of the sizing file at the knowledge root.
pub const SIZING_FILE: &str = "sizing.ron";

/// Default resources when a set-up names none.
pub const DEFAULT_MACHINE: &str = "hsm_5axis";
pub const DEFAULT_TOOL_SET: &str = "alu_hsm";
pub const DEFAULT_MATERIAL: &str = "al7075";
pub const DEFAULT_POST: &str = "linuxcnc";

/// The folders of one-item-per-file knowledge, by id.
pub const ITEM_FOLDERS: [&str; 4] = ["machines", "tools", "materials", "posts"];

#[derive(Default)]
struct Collector {
    k: Option<Knowledge>,
    errors: Vec<KnowledgeError>,
    /// Each material's file and text by id, to point cross-file problems
    /// (feeds) at its values.
    material_files: BTreeMap<String, (PathBuf, String)>,
}

/// Runs `check` on a parsed value and records its problems, each located
/// in the file's text.
fn located<T>(
    errors: &mut Vec<KnowledgeError>,
    path: &Path,
    text: &str,
    value: &T,
    check: impl Fn(&T, &mut check::Checks),
) {
    let mut c = check::Checks::default();
    check(value, &mut c);
    for p in c.out {
        errors.push(KnowledgeError::at_value(path, text, p));
    }
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
        let e = &mut errors;
        let sizing = parse_root(&root, SIZING_FILE, origin, e, SizingKnowledge::checks);
        let walls = parse_root(&root, ROOT_FILES[1], origin, e, WallRecognition::checks);
        let depressions = parse_root(
            &root,
            ROOT_FILES[2],
            origin,
            e,
            DepressionRecognition::checks,
        );
        let sequencing = parse_root(
            &root,
            SEQUENCING_FILE,
            origin,
            e,
            SequencingKnowledge::checks,
        );
        let strategies = parse_root(&root, STRATEGIES_FILE, origin, e, StrategyKnowledge::checks);
        let interference = parse_root(
            &root,
            INTERFERENCE_FILE,
            origin,
            e,
            InterferenceKnowledge::checks,
        );
        let methods = parse_root(&root, METHODS_FILE, origin, e, MethodKnowledge::checks);
        let verification = parse_root(
            &root,
            VERIFICATION_FILE,
            origin,
            e,
            |v: &VerificationKnowledge, c| {
                for (field, reason) in v.problems() {
                    c.push(vec![Seg::Field(field)], reason);
                }
            },
        );
        let (
            Some(sizing),
            Some(wall_recognition),
            Some(depression_recognition),
            Some(sequencing),
            Some(strategies),
            Some(interference),
            Some(methods),
            Some(verification),
        ) = (
            sizing,
            walls,
            depressions,
            sequencing,
            strategies,
            interference,
            methods,
            verification,
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
                verification,
            }),
            errors,
            material_files: BTreeMap::new(),
        };
        for (path, text, parent) in rest {
            match parent.as_str() {
                "machines" => {
                    c.add(
                        path,
                        text,
                        |k| &mut k.machines,
                        |m: &Machine| &m.id,
                        Machine::checks,
                    );
                }
                "tools" => {
                    c.add(
                        path,
                        text,
                        |k| &mut k.tool_sets,
                        |t: &ToolSet| &t.id,
                        ToolSet::checks,
                    );
                }
                "materials" => {
                    if let Some(id) = c.add(
                        path,
                        text,
                        |k| &mut k.materials,
                        |m: &Material| &m.id,
                        Material::checks,
                    ) {
                        c.material_files.insert(id, (path.clone(), text.clone()));
                    }
                }
                "posts" => {
                    c.add(
                        path,
                        text,
                        |k| &mut k.posts,
                        |p: &PostProcessor| &p.id,
                        PostProcessor::checks,
                    );
                }
                _ => c.errors.push(KnowledgeError::Invalid {
                    path: path.clone(),
                    reason:
                        "not in a known knowledge folder (machines/, tools/, materials/, posts/)"
                            .into(),
                }),
            }
        }
        let Some(k) = c.k.take() else {
            return Err(c.errors);
        };
        let mut errors = c.errors;
        let interference_file = root.get(INTERFERENCE_FILE).copied();
        errors.extend(validate(&k, interference_file, &c.material_files));
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
    check: impl Fn(&T, &mut check::Checks),
) -> Option<T> {
    match root.get(name) {
        Some((path, text)) => match parse_ron::<T>(text, path) {
            Ok(v) => {
                located(errors, path, text, &v, check);
                Some(v)
            }
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
    /// Parses, checks and files one item; its id when it was added.
    fn add<T: serde::de::DeserializeOwned>(
        &mut self,
        path: &Path,
        text: &str,
        map: impl Fn(&mut Knowledge) -> &mut BTreeMap<String, T>,
        id: impl Fn(&T) -> &String,
        check: impl Fn(&T, &mut check::Checks),
    ) -> Option<String> {
        match parse_ron::<T>(text, path) {
            Ok(item) => {
                located(&mut self.errors, path, text, &item, check);
                let key = id(&item).clone();
                let k = self.k.as_mut()?;
                match map(k).entry(key.clone()) {
                    Entry::Occupied(e) => self.errors.push(KnowledgeError::Invalid {
                        path: path.to_path_buf(),
                        reason: format!(
                            "duplicate id `{}` (already defined by another file)",
                            e.key()
                        ),
                    }),
                    Entry::Vacant(e) => {
                        e.insert(item);
                        return Some(key);
                    }
                }
                None
            }
            Err(e) => {
                self.errors.push(e);
                None
            }
        }
    }
}

fn invalid(what: &str, reason: String) -> KnowledgeError {
    KnowledgeError::Invalid {
        path: PathBuf::from(what),
        reason,
    }
}

/// The lowest feed (mm/min) a tool may get: a slower one prints as `F0`
/// (or rounds to a feed the control refuses).
pub const MIN_FEED: f64 = 1.0;

/// Checks across files: references between files and the feeds that tools,
/// materials, machines and methods give together. Each file's own values
/// are checked where it is read.
fn validate(
    k: &Knowledge,
    interference: Option<(&PathBuf, &String)>,
    materials: &BTreeMap<String, (PathBuf, String)>,
) -> Vec<KnowledgeError> {
    let mut errors = Vec::new();
    // Rules that name a strategy block must name one that exists.
    let selectors = k
        .interference
        .keep_order
        .iter()
        .enumerate()
        .map(|(i, r)| {
            (
                at!["keep_order", i, "select", "block"],
                format!("keep_order rule `{}`", r.id),
                &r.select,
            )
        })
        .chain(
            k.interference
                .narrow_remaining_joins
                .iter()
                .enumerate()
                .map(|(i, s)| {
                    (
                        at!["narrow_remaining_joins", i, "block"],
                        format!("narrow_remaining_joins entry {}", i + 1),
                        s,
                    )
                }),
        );
    for (place, what, select) in selectors {
        if let FeatureSelector::Block { block, .. } = select {
            let known = k
                .strategies
                .strategies
                .iter()
                .flat_map(|s| s.blocks.iter())
                .any(|b| b.id() == block);
            if !known {
                let reason = format!(
                    "{what} selects block `{block}`, which no strategy in strategies.ron has"
                );
                errors.push(match interference {
                    Some((path, text)) => KnowledgeError::at_value(
                        path,
                        text,
                        Problem {
                            at: place,
                            message: reason,
                        },
                    ),
                    None => invalid("interference knowledge (interference.ron)", reason),
                });
            }
        }
    }
    // The slowest feed any tool gets: finishing feed per tooth, one flute
    // per tooth, the spindle speed the cutting speed gives (capped by the
    // machine), capped by the slower table axis, times the link factor
    // when that is below 1. Reported once per material and tool.
    let link = k.methods.link_feed_factor.min(1.0);
    for m in k.materials.values() {
        let c = &m.cutting;
        for set in k.tool_sets.values() {
            for t in &set.tools {
                let slowest = k
                    .machines
                    .values()
                    .map(|mc| {
                        let rpm = (1000.0 * c.cutting_speed / (std::f64::consts::PI * t.diameter))
                            .min(mc.spindle_max_rpm);
                        let vmax = 60.0 * mc.x.v_max.min(mc.y.v_max);
                        let fz = c.feed_per_tooth_finishing.min(c.feed_per_tooth_roughing);
                        ((fz * f64::from(t.flutes) * rpm).min(vmax) * link, &mc.id)
                    })
                    .min_by(|a, b| a.0.total_cmp(&b.0));
                let Some((feed, machine)) = slowest else {
                    continue;
                };
                // Values already refused (NaN, zero) are not reported twice.
                if !feed.is_finite() || feed <= 0.0 || feed >= MIN_FEED {
                    continue;
                }
                let reason = format!(
                    "material `{}`: with tool `{}` (set `{}`) on machine `{machine}` the slowest \
                     feed is {feed:.4} mm/min, below {MIN_FEED} mm/min (it would print F0): \
                     raise the feed per tooth or cutting speed",
                    m.id, t.id, set.id
                );
                errors.push(match materials.get(&m.id) {
                    Some((path, text)) => KnowledgeError::at_value(
                        path,
                        text,
                        Problem {
                            at: at!["cutting", "feed_per_tooth_finishing"],
                            message: reason,
                        },
                    ),
                    None => invalid(&format!("material `{}`", m.id), reason),
                });
            }
        }
    }
    errors
}
