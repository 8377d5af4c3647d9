//! Stiffness-feature sequencing rules (thesis §4.2.2–4.2.3, §5.3.2, §6.2.1),
//! read from `knowledge/sequencing.ron`.
//!
//! A rule says: when an ordered pair of stiffness features `(first, second)`
//! satisfies a condition, `first` is machined before `second`, or both are
//! machined together. Rules are applied to the whole part in priority order
//! (highest first) by `thinplan-sequence`; a rule whose constraint would
//! contradict a stronger one is refused and the refusal recorded. This
//! module is only the rules' data and the checks on it.
//!
//! The condition is a small typed tree ([`PairCondition`]): `All`, `Any` and
//! `Not` of atoms about the kinds and roles of the two features, their
//! connection, their position along the spindle axis and their orientation.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use crate::at;
use crate::check::{Checks, Seg};

/// The name of the sequencing file at the knowledge root.
pub const SEQUENCING_FILE: &str = "sequencing.ron";

/// All sequencing rules.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SequencingKnowledge {
    /// The rules, in any order: they are applied by priority.
    pub rules: Vec<SequencingRule>,
}

/// One pair rule.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SequencingRule {
    /// Unique id; constraints made by the rule carry `sequencing.<id>` as
    /// their provenance rule.
    pub id: String,
    /// Unique; higher is stronger and applied first.
    pub priority: i32,
    /// When the rule applies to the ordered pair `(first, second)`.
    pub when: PairCondition,
    /// What it then imposes on the pair.
    pub then: SequenceAction,
    /// A sentence for explanations (e.g. the thesis section).
    #[serde(default)]
    pub note: String,
}

/// What a rule imposes on `(first, second)`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum SequenceAction {
    /// `first` is machined before `second`.
    Before,
    /// `first` and `second` are machined together (one simultaneous group).
    Simultaneous,
    /// `first` before `second`, unless the condition holds at the moment the
    /// rule is applied (it may look at the constraints already made).
    BeforeUnless(PairCondition),
}

/// A condition on an ordered pair of stiffness features.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum PairCondition {
    /// Every condition holds (must not be empty).
    All(Vec<PairCondition>),
    /// At least one condition holds (must not be empty).
    Any(Vec<PairCondition>),
    /// The condition does not hold.
    Not(Box<PairCondition>),
    /// A test on `first` alone.
    First(FeatureTest),
    /// A test on `second` alone.
    Second(FeatureTest),
    /// How the two are connected (stage 3's connection graph).
    Related(Relation),
    /// `first` lies higher than `second` along the set-up's up axis (the
    /// spindle axis): `level(first) − level(second) > by_more_than` (mm).
    /// False when either feature has no shape.
    Higher { level: Level, by_more_than: f64 },
    /// The line along which the two features meet (the cross product of
    /// their axes: for walls, their normals) runs horizontally or vertically
    /// with respect to up, within `within_deg` degrees. False when the axes
    /// are parallel. A rib on a wall "oriented horizontally with respect to
    /// that wall" (§4.2.2) meets it along a horizontal line.
    Junction { runs: Orientation, within_deg: f64 },
    /// `second` already has at least `at_least` leaves other than `first`
    /// (connected to it as base–leaf, matching `leaf`) that are sequenced
    /// before it, by the constraints made so far. Used to keep support: the
    /// thesis's "multiple vertical ribs in a row on a wall all machined
    /// before that wall" (§4.2.2).
    SecondHasLeavesBefore { leaf: FeatureTest, at_least: u32 },
}

/// A test on one stiffness feature.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum FeatureTest {
    /// Any feature.
    Any,
    /// Its kind is one of these (must not be empty).
    Kind(Vec<FeatureKind>),
    /// It is a wall with one of these roles (must not be empty).
    Role(Vec<RoleName>),
    /// A depression: hole, cut-out, slot, notch, pocket or step.
    Depression,
    /// A detail: chamfer or fillet.
    Detail,
}

/// The stiffness-feature kinds (mirror of the plan's `StiffnessKind`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Serialize, Deserialize)]
pub enum FeatureKind {
    Wall,
    Hole,
    Cutout,
    Slot,
    Notch,
    Pocket,
    Step,
    Chamfer,
    Fillet,
}

/// Wall roles (mirror of the plan's `WallRole`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Serialize, Deserialize)]
pub enum RoleName {
    Web,
    Rib,
    Flange,
}

/// A connection between the two features of a pair.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Relation {
    /// `first` is a leaf of `second` (stands on it, or is a depression in it).
    FirstOnSecond,
    /// `second` is a leaf of `first`.
    SecondOnFirst,
    /// A base–leaf connection either way.
    BaseLeaf,
    /// A crossing connection.
    Crossing,
    /// Any connection.
    Connected,
}

/// Which level of a feature's extent along up is compared.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Level {
    /// Its highest point.
    Top,
    /// Its lowest point.
    Bottom,
    /// Midway between the two.
    Middle,
}

/// Horizontal (perpendicular to up) or vertical (along up).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Orientation {
    Horizontal,
    Vertical,
}

impl SequencingKnowledge {
    /// Problems a parser cannot find: duplicate ids and priorities, empty
    /// ids and lists, numbers out of range. Each names the rule.
    pub fn problems(&self) -> Vec<String> {
        let mut c = Checks::default();
        self.checks(&mut c);
        c.messages()
    }

    /// The problems, each at its place in `sequencing.ron`.
    pub fn checks(&self, c: &mut Checks) {
        let mut ids: BTreeMap<&str, usize> = BTreeMap::new();
        let mut priorities: BTreeMap<i32, &str> = BTreeMap::new();
        for (i, r) in self.rules.iter().enumerate() {
            let name = if r.id.is_empty() {
                c.push(
                    at!["rules", i, "id"],
                    format!("rule #{} has an empty id", i + 1),
                );
                format!("#{}", i + 1)
            } else {
                format!("`{}`", r.id)
            };
            if !r.id.is_empty() && ids.insert(&r.id, i).is_some() {
                c.push(at!["rules", i, "id"], format!("rule {name}: duplicate id"));
            }
            if let Some(other) = priorities.insert(r.priority, &r.id) {
                c.push(
                    at!["rules", i, "priority"],
                    format!(
                        "rule {name}: duplicate priority {} (also rule `{other}`): \
                         priorities must be unique so the order of application is defined",
                        r.priority
                    ),
                );
            }
            let mut problems = Checks::default();
            condition_problems(&r.when, at!["rules", i, "when"], &mut problems);
            if let SequenceAction::BeforeUnless(cond) = &r.then {
                condition_problems(cond, at!["rules", i, "then"], &mut problems);
            }
            for p in problems.out {
                c.push(p.at, format!("rule {name}: {}", p.message));
            }
        }
    }
}

fn test_problems(t: &FeatureTest, at: Vec<Seg>, c: &mut Checks) {
    match t {
        FeatureTest::Kind(k) if k.is_empty() => c.push(at, "`Kind([])` matches nothing".into()),
        FeatureTest::Role(r) if r.is_empty() => c.push(at, "`Role([])` matches nothing".into()),
        _ => {}
    }
}

fn with(at: &[Seg], s: Seg) -> Vec<Seg> {
    let mut v = at.to_vec();
    v.push(s);
    v
}

fn condition_problems(cond: &PairCondition, at: Vec<Seg>, c: &mut Checks) {
    match cond {
        PairCondition::All(v) | PairCondition::Any(v) => {
            if v.is_empty() {
                c.push(
                    at.clone(),
                    "an empty `All`/`Any` list (write the condition out)".into(),
                );
            }
            for (i, x) in v.iter().enumerate() {
                condition_problems(x, with(&at, Seg::Index(i)), c);
            }
        }
        // `Not(…)`, `First(…)` are looked through by the locator.
        PairCondition::Not(x) => condition_problems(x, at, c),
        PairCondition::First(t) | PairCondition::Second(t) => test_problems(t, at, c),
        PairCondition::Related(_) => {}
        PairCondition::Higher { by_more_than, .. } => {
            if !by_more_than.is_finite() || *by_more_than < 0.0 {
                c.push(
                    with(&at, Seg::Field("by_more_than")),
                    format!("`Higher.by_more_than` must be a number ≥ 0 mm, not {by_more_than}"),
                );
            }
        }
        PairCondition::Junction { within_deg, .. } => {
            if !(within_deg.is_finite() && (0.0..=45.0).contains(within_deg)) {
                c.push(
                    with(&at, Seg::Field("within_deg")),
                    format!("`Junction.within_deg` must lie in 0..=45 degrees, not {within_deg}"),
                );
            }
        }
        PairCondition::SecondHasLeavesBefore { leaf, at_least } => {
            test_problems(leaf, with(&at, Seg::Field("leaf")), c);
            if *at_least == 0 {
                c.push(
                    with(&at, Seg::Field("at_least")),
                    "`SecondHasLeavesBefore.at_least` 0 always holds".into(),
                );
            }
        }
    }
}
