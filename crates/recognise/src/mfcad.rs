//! Scoring recognition on the MFCAD dataset (per-face machining-feature
//! labels on 10 mm blocks), see `crates/recognise/MFCAD.md`.
//!
//! # Mapping our features to MFCAD's 16 classes
//!
//! | our feature (kind, rule, attributes)                              | MFCAD class                 |
//! |-------------------------------------------------------------------|-----------------------------|
//! | `chamfer`                                                         | chamfer                     |
//! | `hole` without floor, 3 / 4 / 6 profile sides                     | triangular / rectangular / 6sides_passage |
//! | `slot.opening` (a long through opening: two parallel sides + ends) | rectangular_passage (by sides, as holes)  |
//! | `pocket` (closed ring + floor), 3 / 4 / 6 sides                   | triangular / rectangular / 6sides_pocket  |
//! | `slot.through` (floor, two facing sides)                          | rectangular_through_slot    |
//! | `slot.v` (no floor, two inclined sides)                           | triangular_through_slot     |
//! | `slot.blind` (floor, three sides or more, open chain)             | rectangular_blind_slot      |
//! | `step.through` (floor, one side), floor outline with 4+ corners   | rectangular_through_step    |
//! | `step.through`, floor outline a triangle                          | triangular_blind_step       |
//! | `step.slanted` (one side leaning away from the floor)             | slanted_through_step        |
//! | `step.blind` (floor, two sides at a right-angled corner)          | rectangular_blind_step      |
//! | `step.two_sided` (floor, two sides at another angle)              | 2sides_through_step         |
//! | `notch` (no floor, two sides at a right angle)                    | triangular_through_slot (nearest) |
//! | `cutout` (no floor, three sides or more, open)                    | rectangular_through_slot (nearest) |
//! | `fillet`, `wall`, any face in no feature                          | stock                       |
//!
//! Side counts other than 3, 4, 6 go to the nearest shape by corner angle:
//! all right angles rectangular, a corner under 75° triangular, else 6sides.
//!
//! # The label names in the shared copy are permuted
//!
//! The `NAME.labels.json` files name classes in the order of the data
//! README (`rectangular_through_slot`, `triangular_through_slot`, …), but
//! the geometry shows that the generator's class ids follow the order of the
//! 25-class list (AAGNet's, restricted to the 16 planar classes: `chamfer`,
//! `triangular_passage`, `rectangular_passage`, …). For example all 32 faces
//! labelled `rectangular_through_slot` are single inclined faces on the
//! convex hull with only convex edges (chamfers), and all faces labelled
//! `chamfer` are axis-parallel faces in sets of three meeting at concave
//! edges (rectangular blind steps). [`true_class`] undoes the permutation;
//! scores are in the true classes.

use std::collections::BTreeMap;
use std::path::Path;

use glam::DVec3;
use thinplan_plan::{StiffnessFeature, StiffnessKind};

/// MFCAD's class names, in the order the shared README and the labels use.
pub const LABEL_NAMES: [&str; 16] = [
    "rectangular_through_slot",
    "triangular_through_slot",
    "rectangular_passage",
    "triangular_passage",
    "6sides_passage",
    "rectangular_through_step",
    "2sides_through_step",
    "slanted_through_step",
    "rectangular_blind_step",
    "triangular_blind_step",
    "rectangular_blind_slot",
    "rectangular_pocket",
    "triangular_pocket",
    "6sides_pocket",
    "chamfer",
    "stock",
];

/// The classes the geometry of label id `i` actually has (the generator's
/// order: the 25-class list restricted to planar features).
pub const TRUE_NAMES: [&str; 16] = [
    "chamfer",
    "triangular_passage",
    "rectangular_passage",
    "6sides_passage",
    "triangular_through_slot",
    "rectangular_through_slot",
    "rectangular_through_step",
    "2sides_through_step",
    "slanted_through_step",
    "triangular_pocket",
    "rectangular_pocket",
    "6sides_pocket",
    "rectangular_blind_slot",
    "triangular_blind_step",
    "rectangular_blind_step",
    "stock",
];

/// The true class of a label name from a `labels.json` file.
pub fn true_class(label: &str) -> Option<&'static str> {
    LABEL_NAMES
        .iter()
        .position(|n| *n == label)
        .map(|i| TRUE_NAMES[i])
}

/// Per-class and overall face accuracy over a directory of MFCAD parts.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct MfcadScore {
    pub parts: usize,
    pub faces: usize,
    pub correct: usize,
    /// True class → (correct faces, faces).
    pub per_class: BTreeMap<String, (usize, usize)>,
    /// (true class, predicted class) → faces.
    pub confusion: BTreeMap<(String, String), usize>,
    /// Faces a wall lists whose true class is not stock (they may also be
    /// faces of a depression: walls and depressions share faces).
    pub wall_claimed_feature_faces: usize,
    /// Faces walls list in all.
    pub wall_claimed_faces: usize,
    /// Parts that could not be read or scored, with the reason.
    pub errors: Vec<String>,
    /// Misclassified faces: `part face-name truth predicted`.
    pub misses: Vec<String>,
}

impl MfcadScore {
    pub fn overall(&self) -> f64 {
        if self.faces == 0 {
            0.0
        } else {
            self.correct as f64 / self.faces as f64
        }
    }

    pub fn class_accuracy(&self, class: &str) -> Option<f64> {
        self.per_class
            .get(class)
            .map(|(c, n)| *c as f64 / (*n).max(1) as f64)
    }

    /// The per-class table, as printed by tests and the CLI.
    pub fn table(&self) -> String {
        let mut s = format!(
            "{:<26} {:>6} {:>6} {:>8}\n",
            "class", "faces", "right", "accuracy"
        );
        for (c, (ok, n)) in &self.per_class {
            s += &format!(
                "{:<26} {:>6} {:>6} {:>7.2}%\n",
                c,
                n,
                ok,
                100.0 * *ok as f64 / (*n).max(1) as f64
            );
        }
        s += &format!(
            "{:<26} {:>6} {:>6} {:>7.2}%  ({} parts)\n",
            "overall",
            self.faces,
            self.correct,
            100.0 * self.overall(),
            self.parts
        );
        s
    }

    /// Confusions off the diagonal, most frequent first.
    pub fn confusion_table(&self) -> String {
        let mut off: Vec<_> = self.confusion.iter().filter(|((t, p), _)| t != p).collect();
        off.sort_by(|a, b| b.1.cmp(a.1).then(a.0.cmp(b.0)));
        let mut s = String::from("truth -> predicted: faces\n");
        for ((t, p), n) in off {
            s += &format!("{t} -> {p}: {n}\n");
        }
        s
    }
}

fn value(f: &StiffnessFeature, name: &str) -> f64 {
    f.provenance.values.get(name).copied().unwrap_or(0.0)
}

/// The nearest shape for a profile with `sides` sides.
fn shape_name(f: &StiffnessFeature) -> &'static str {
    match value(f, "sides") as usize {
        3 => "triangular",
        4 => "rectangular",
        6 => "6sides",
        _ => {
            if value(f, "right_corners") > 0.5 {
                "rectangular"
            } else if value(f, "min_corner_deg") < 75.0 {
                "triangular"
            } else {
                "6sides"
            }
        }
    }
}

/// The MFCAD class of one of our features (see the module table).
pub fn mfcad_class(f: &StiffnessFeature) -> String {
    let rule = f.provenance.rule.as_str();
    match f.kind {
        StiffnessKind::Chamfer => "chamfer".into(),
        StiffnessKind::Hole => format!("{}_passage", shape_name(f)),
        StiffnessKind::Pocket => format!("{}_pocket", shape_name(f)),
        StiffnessKind::Slot => match rule {
            // A long through opening (our slot) is a passage to MFCAD.
            "recognise.slot.opening" => format!("{}_passage", shape_name(f)),
            "recognise.slot.v" => "triangular_through_slot".into(),
            "recognise.slot.blind" => "rectangular_blind_slot".into(),
            _ => "rectangular_through_slot".into(),
        },
        StiffnessKind::Step => match rule {
            "recognise.step.slanted" => "slanted_through_step".into(),
            "recognise.step.blind" => "rectangular_blind_step".into(),
            "recognise.step.two_sided" => "2sides_through_step".into(),
            _ if value(f, "floor_corners") as usize == 3 => "triangular_blind_step".into(),
            _ => "rectangular_through_step".into(),
        },
        StiffnessKind::Notch => "triangular_through_slot".into(),
        StiffnessKind::Cutout => "rectangular_through_slot".into(),
        StiffnessKind::Wall | StiffnessKind::Fillet => "stock".into(),
    }
}

/// Reads every `*.step` with its `*.labels.json` in `dir` (through `read`,
/// e.g. `thinplan_step::read_step_file`), recognises it with the builtin
/// knowledge (up = +z) and scores the faces.
///
/// (`thinplan-step` is a dev-dependency of this crate, so the reader is
/// passed in; `score_mfcad(dir)` becomes a one-line wrapper once it is a
/// normal dependency.)
pub fn score_mfcad_with(
    dir: &Path,
    read: impl Fn(&Path) -> Result<thinplan_brep::Brep, String>,
) -> MfcadScore {
    score(dir, &read, true)
}

/// As [`score_mfcad_with`], but with the depression recogniser alone (no
/// walls): the score of the depression rules.
pub fn score_mfcad_depressions_with(
    dir: &Path,
    read: impl Fn(&Path) -> Result<thinplan_brep::Brep, String>,
) -> MfcadScore {
    score(dir, &read, false)
}

fn score(
    dir: &Path,
    read: &dyn Fn(&Path) -> Result<thinplan_brep::Brep, String>,
    walls: bool,
) -> MfcadScore {
    let mut score = MfcadScore::default();
    let k = match thinplan_knowledge::Knowledge::builtin() {
        Ok(k) => k,
        Err(e) => {
            score.errors.push(format!("knowledge: {e:?}"));
            return score;
        }
    };
    let Some(machine) = k.machine(thinplan_knowledge::DEFAULT_MACHINE).cloned() else {
        score.errors.push("no default machine".into());
        return score;
    };
    let mut paths: Vec<_> = match std::fs::read_dir(dir) {
        Ok(rd) => rd
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.extension().is_some_and(|x| x == "step"))
            .collect(),
        Err(e) => {
            score.errors.push(format!("{}: {e}", dir.display()));
            return score;
        }
    };
    paths.sort();
    for path in paths {
        let stem = path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        let labels_path = dir.join(format!("{stem}.labels.json"));
        let labels: BTreeMap<String, String> = match std::fs::read_to_string(&labels_path)
            .map_err(|e| e.to_string())
            .and_then(|t| serde_json::from_str::<serde_json::Value>(&t).map_err(|e| e.to_string()))
        {
            Ok(v) => v["face_name_to_class"]
                .as_object()
                .map(|o| {
                    o.iter()
                        .filter_map(|(k, v)| v.as_str().map(|s| (k.clone(), s.to_string())))
                        .collect()
                })
                .unwrap_or_default(),
            Err(e) => {
                score.errors.push(format!("{}: {e}", labels_path.display()));
                continue;
            }
        };
        let brep = match read(&path) {
            Ok(b) => b,
            Err(e) => {
                score.errors.push(format!("{}: {e}", path.display()));
                continue;
            }
        };
        let features = if walls {
            crate::recognise(&brep, DVec3::Z, &k, &machine).features
        } else {
            let adjacency = thinplan_brep::edge_adjacency(&brep);
            crate::depressions::find_depressions(
                &brep,
                &adjacency,
                DVec3::Z,
                &k.depression_recognition,
                &[],
                &mut Vec::new(),
            )
        };
        let mut predicted = vec!["stock".to_string(); brep.faces.len()];
        let mut wall = vec![false; brep.faces.len()];
        // A face's class is the class of the depression or detail holding
        // it, else stock (walls are stock; they may share faces with
        // depressions).
        for f in &features {
            for &face in &f.faces {
                if face < predicted.len() {
                    if f.kind == StiffnessKind::Wall {
                        wall[face] = true;
                    } else {
                        predicted[face] = mfcad_class(f);
                    }
                }
            }
        }
        score.parts += 1;
        for (i, face) in brep.faces.iter().enumerate() {
            let Some(label) = labels.get(&face.name) else {
                score
                    .errors
                    .push(format!("{stem}: face {i} '{}' has no label", face.name));
                continue;
            };
            let truth = true_class(label).unwrap_or("unknown").to_string();
            let p = &predicted[i];
            score.faces += 1;
            let e = score.per_class.entry(truth.clone()).or_default();
            e.1 += 1;
            if *p == truth {
                e.0 += 1;
                score.correct += 1;
            } else {
                score
                    .misses
                    .push(format!("{stem} {} {truth} {p}", face.name));
            }
            if wall[i] {
                score.wall_claimed_faces += 1;
                if truth != "stock" {
                    score.wall_claimed_feature_faces += 1;
                }
            }
            *score.confusion.entry((truth, p.clone())).or_default() += 1;
        }
    }
    score
}
