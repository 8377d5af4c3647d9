//! Evaluating a rule's pair condition on two features.

use std::collections::BTreeMap;

use glam::{DVec2, DVec3};
use thinplan_knowledge::{
    FeatureKind, FeatureTest, Level, Orientation, PairCondition, Relation, RoleName,
};
use thinplan_plan::{
    ConnectionKind, Prism, ProfileLoop, StiffnessFeature, StiffnessKind, WallRole,
};

use crate::state::State;

/// What the rules need of one feature, in the set-up frame.
pub(crate) struct Facts {
    pub kind: FeatureKind,
    pub role: Option<RoleName>,
    /// Unit axis (wall normal, depression axis), or zero.
    pub axis: DVec3,
    /// Lowest and highest point along up, when the feature has a shape.
    pub extent: Option<(f64, f64)>,
}

impl Facts {
    pub fn of(f: &StiffnessFeature, up: DVec3) -> Facts {
        Facts {
            kind: kind_name(f.kind),
            role: f.role.map(role_name),
            axis: f.axis.normalize_or_zero(),
            extent: f.shape.as_ref().and_then(|p| extent_along(p, up)),
        }
    }

    fn level(&self, l: Level) -> Option<f64> {
        let (lo, hi) = self.extent?;
        Some(match l {
            Level::Top => hi,
            Level::Bottom => lo,
            Level::Middle => 0.5 * (lo + hi),
        })
    }
}

fn kind_name(k: StiffnessKind) -> FeatureKind {
    match k {
        StiffnessKind::Wall => FeatureKind::Wall,
        StiffnessKind::Hole => FeatureKind::Hole,
        StiffnessKind::Cutout => FeatureKind::Cutout,
        StiffnessKind::Slot => FeatureKind::Slot,
        StiffnessKind::Notch => FeatureKind::Notch,
        StiffnessKind::Pocket => FeatureKind::Pocket,
        StiffnessKind::Step => FeatureKind::Step,
        StiffnessKind::Chamfer => FeatureKind::Chamfer,
        StiffnessKind::Fillet => FeatureKind::Fillet,
    }
}

fn role_name(r: WallRole) -> RoleName {
    match r {
        WallRole::Web => RoleName::Web,
        WallRole::Rib => RoleName::Rib,
        WallRole::Flange => RoleName::Flange,
    }
}

/// Lowest and highest point of a prism along `up` (unit); arcs are sampled.
pub(crate) fn extent_along(p: &Prism, up: DVec3) -> Option<(f64, f64)> {
    let fz = p.frame.z.try_normalize()?;
    let fx = p.frame.x.try_normalize()?;
    let fy = fz.cross(fx);
    let mut pts = Vec::new();
    loop_points(&p.region.outer, &mut pts);
    if pts.is_empty() || !(p.z_min.is_finite() && p.z_max.is_finite()) {
        return None;
    }
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for q in pts {
        for z in [p.z_min, p.z_max] {
            let h = (p.frame.origin + fx * q.x + fy * q.y + fz * z).dot(up);
            lo = lo.min(h);
            hi = hi.max(h);
        }
    }
    (lo.is_finite() && hi.is_finite()).then_some((lo, hi))
}

/// The vertices of a loop with its arcs sampled (bulge convention of the plan).
fn loop_points(l: &ProfileLoop, out: &mut Vec<DVec2>) {
    let n = l.vertices.len();
    for (i, v) in l.vertices.iter().enumerate() {
        let p0 = DVec2::new(v.x, v.y);
        out.push(p0);
        if v.bulge == 0.0 || !v.bulge.is_finite() {
            continue;
        }
        let w = &l.vertices[(i + 1) % n];
        let p1 = DVec2::new(w.x, w.y);
        let chord = p1 - p0;
        let len = chord.length();
        if len <= 0.0 {
            continue;
        }
        let b = v.bulge;
        let left = DVec2::new(-chord.y, chord.x) / len;
        let centre = (p0 + p1) * 0.5 + left * (len * 0.5) * ((1.0 - b * b) / (2.0 * b));
        let r = (p0 - centre).length();
        let a0 = (p0 - centre).to_angle();
        let sweep = 4.0 * b.atan();
        const SAMPLES: usize = 32;
        for k in 1..SAMPLES {
            let a = a0 + sweep * k as f64 / SAMPLES as f64;
            out.push(centre + DVec2::from_angle(a) * r);
        }
    }
}

/// Everything a condition can look at.
pub(crate) struct Ctx<'a> {
    pub facts: &'a [Facts],
    /// Connections by (base, leaf) index.
    pub links: &'a BTreeMap<(usize, usize), ConnectionKind>,
    /// Base–leaf leaves of each feature, sorted.
    pub leaves: &'a [Vec<usize>],
    pub up: DVec3,
    pub state: &'a State,
}

/// Values a condition used, by name (recorded in provenance).
pub(crate) type Values = BTreeMap<String, f64>;

fn test(t: &FeatureTest, f: &Facts) -> bool {
    match t {
        FeatureTest::Any => true,
        FeatureTest::Kind(ks) => ks.contains(&f.kind),
        FeatureTest::Role(rs) => {
            f.kind == FeatureKind::Wall && f.role.is_some_and(|r| rs.contains(&r))
        }
        FeatureTest::Depression => matches!(
            f.kind,
            FeatureKind::Hole
                | FeatureKind::Cutout
                | FeatureKind::Slot
                | FeatureKind::Notch
                | FeatureKind::Pocket
                | FeatureKind::Step
        ),
        FeatureTest::Detail => matches!(f.kind, FeatureKind::Chamfer | FeatureKind::Fillet),
    }
}

fn level_name(l: Level) -> &'static str {
    match l {
        Level::Top => "top",
        Level::Bottom => "bottom",
        Level::Middle => "middle",
    }
}

/// Whether `c` holds for `(a, b)`; `values` (when given) receives the
/// numbers the evaluated atoms used.
pub(crate) fn holds(
    c: &PairCondition,
    a: usize,
    b: usize,
    cx: &Ctx,
    mut values: Option<&mut Values>,
) -> bool {
    match c {
        PairCondition::All(v) => v.iter().all(|c| holds(c, a, b, cx, values.as_deref_mut())),
        PairCondition::Any(v) => v.iter().any(|c| holds(c, a, b, cx, values.as_deref_mut())),
        PairCondition::Not(c) => !holds(c, a, b, cx, values),
        PairCondition::First(t) => test(t, &cx.facts[a]),
        PairCondition::Second(t) => test(t, &cx.facts[b]),
        PairCondition::Related(r) => {
            let base_leaf = |base: usize, leaf: usize| {
                cx.links.get(&(base, leaf)) == Some(&ConnectionKind::BaseLeaf)
            };
            let crossing = || {
                cx.links.get(&(a, b)) == Some(&ConnectionKind::Crossing)
                    || cx.links.get(&(b, a)) == Some(&ConnectionKind::Crossing)
            };
            match r {
                Relation::FirstOnSecond => base_leaf(b, a),
                Relation::SecondOnFirst => base_leaf(a, b),
                Relation::BaseLeaf => base_leaf(a, b) || base_leaf(b, a),
                Relation::Crossing => crossing(),
                Relation::Connected => {
                    cx.links.contains_key(&(a, b)) || cx.links.contains_key(&(b, a))
                }
            }
        }
        PairCondition::Higher {
            level,
            by_more_than,
        } => {
            let (Some(la), Some(lb)) = (cx.facts[a].level(*level), cx.facts[b].level(*level))
            else {
                return false;
            };
            if let Some(v) = values {
                let n = level_name(*level);
                v.insert(format!("first.{n}"), la);
                v.insert(format!("second.{n}"), lb);
                v.insert("higher_by".into(), la - lb);
                v.insert("by_more_than".into(), *by_more_than);
            }
            la - lb > *by_more_than
        }
        PairCondition::Junction { runs, within_deg } => {
            let line = cx.facts[a].axis.cross(cx.facts[b].axis);
            let Some(line) = line.try_normalize().filter(|_| line.length() > 1e-6) else {
                return false;
            };
            // Angle of the junction line above the horizontal plane.
            let elevation = line.dot(cx.up).abs().clamp(0.0, 1.0).asin().to_degrees();
            if let Some(v) = values {
                v.insert("junction_elevation_deg".into(), elevation);
                v.insert("within_deg".into(), *within_deg);
            }
            match runs {
                Orientation::Horizontal => elevation <= *within_deg,
                Orientation::Vertical => 90.0 - elevation <= *within_deg,
            }
        }
        PairCondition::SecondHasLeavesBefore { leaf, at_least } => {
            let count = cx.leaves[b]
                .iter()
                .filter(|&&l| l != a && test(leaf, &cx.facts[l]) && cx.state.precedes(l, b))
                .count();
            if let Some(v) = values {
                v.insert("leaves_before_second".into(), count as f64);
                v.insert("at_least".into(), f64::from(*at_least));
            }
            count >= *at_least as usize
        }
    }
}
