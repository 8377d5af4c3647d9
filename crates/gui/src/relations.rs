//! Reading relations out of the plan for the views and the commands on a
//! selection: names, predecessors and successors, owner and owned
//! features, the machining order of the simulation and the deflection
//! read-out. Read-only: no planning decision is made here.

use std::collections::{BTreeSet, VecDeque};

use thinplan_knowledge::{Block, Knowledge};
use thinplan_plan::{
    Constraint, ConstraintKind, MachiningFeature, MachiningFeatureId, Plan, Provenance,
    StiffnessFeature, StiffnessFeatureId, StiffnessKind,
};
use thinplan_sizing::{CutSizes, MillingMode, Piece};

use crate::state::Entity;

/// A short name: `SF3 wall (rib)`, `MF12 of SF3`, `OP4 MF12`.
pub fn name(plan: &Plan, e: Entity) -> String {
    match e {
        Entity::Part => format!("part {}", plan.part.source),
        Entity::Setup => format!("set-up {}", plan.setup.machine),
        Entity::Stiffness(id) => match sf(plan, id) {
            Some(f) => sf_name(f),
            None => format!("{id}"),
        },
        Entity::Machining(id) => match mf(plan, id) {
            Some(f) => format!("{id} of {}", f.owner),
            None => format!("{id}"),
        },
        Entity::Operation(id) => match plan.operations.iter().find(|o| o.id == id) {
            Some(o) => format!("{id} {} {}", o.feature, o.method),
            None => format!("{id}"),
        },
    }
}

pub fn sf_name(f: &StiffnessFeature) -> String {
    let kind = kind_name(f.kind);
    match f.role {
        Some(r) => format!("{} {kind} ({})", f.id, format!("{r:?}").to_lowercase()),
        None => format!("{} {kind}", f.id),
    }
}

pub fn kind_name(k: StiffnessKind) -> &'static str {
    match k {
        StiffnessKind::Wall => "wall",
        StiffnessKind::Hole => "hole",
        StiffnessKind::Cutout => "cut-out",
        StiffnessKind::Slot => "slot",
        StiffnessKind::Notch => "notch",
        StiffnessKind::Pocket => "pocket",
        StiffnessKind::Step => "step",
        StiffnessKind::Chamfer => "chamfer",
        StiffnessKind::Fillet => "fillet",
    }
}

/// Stages write features in id order, so a binary search finds them (views
/// look features up for every row they draw); a plan out of order still
/// finds them by the linear search (ids are unique, so a hit is right).
pub fn sf(plan: &Plan, id: StiffnessFeatureId) -> Option<&StiffnessFeature> {
    let v = &plan.stiffness_features;
    match v.binary_search_by_key(&id, |f| f.id) {
        Ok(i) => Some(&v[i]),
        Err(_) => v.iter().find(|f| f.id == id),
    }
}

pub fn mf(plan: &Plan, id: MachiningFeatureId) -> Option<&MachiningFeature> {
    let v = &plan.machining_features;
    match v.binary_search_by_key(&id, |f| f.id) {
        Ok(i) => Some(&v[i]),
        Err(_) => v.iter().find(|f| f.id == id),
    }
}

pub fn provenance(plan: &Plan, e: Entity) -> Option<&Provenance> {
    match e {
        Entity::Part => None,
        Entity::Setup => Some(&plan.setup.provenance),
        Entity::Stiffness(id) => sf(plan, id).map(|f| &f.provenance),
        Entity::Machining(id) => mf(plan, id).map(|f| &f.provenance),
        Entity::Operation(id) => plan
            .operations
            .iter()
            .find(|o| o.id == id)
            .map(|o| &o.provenance),
    }
}

/// The constraints of the level `e` belongs to, as entity pairs.
fn constraint_pairs(plan: &Plan, e: Entity) -> Vec<(Entity, Entity, ConstraintKind)> {
    fn pairs<I: Copy>(
        cs: &[Constraint<I>],
        wrap: impl Fn(I) -> Entity,
    ) -> Vec<(Entity, Entity, ConstraintKind)> {
        cs.iter()
            .map(|c| (wrap(c.first), wrap(c.second), c.kind))
            .collect()
    }
    match e {
        Entity::Stiffness(_) => pairs(&plan.stiffness_constraints, Entity::Stiffness),
        Entity::Machining(_) => pairs(&plan.machining_constraints, Entity::Machining),
        _ => Vec::new(),
    }
}

/// Direct or transitive predecessors (`forward == false`) or successors
/// along `before` constraints.
pub fn neighbours(plan: &Plan, e: Entity, forward: bool, all: bool) -> BTreeSet<Entity> {
    let pairs = constraint_pairs(plan, e);
    let mut out = BTreeSet::new();
    let mut queue = VecDeque::from([e]);
    while let Some(x) = queue.pop_front() {
        for &(a, b, k) in &pairs {
            if k != ConstraintKind::Before {
                continue;
            }
            let next = if forward && a == x {
                b
            } else if !forward && b == x {
                a
            } else {
                continue;
            };
            if next != e && out.insert(next) && all {
                queue.push_back(next);
            }
        }
    }
    out
}

/// Features machined together with `e` (simultaneous constraints).
pub fn together(plan: &Plan, e: Entity) -> BTreeSet<Entity> {
    constraint_pairs(plan, e)
        .into_iter()
        .filter(|p| p.2 == ConstraintKind::Simultaneous)
        .filter_map(|(a, b, _)| {
            if a == e {
                Some(b)
            } else if b == e {
                Some(a)
            } else {
                None
            }
        })
        .collect()
}

pub fn owner(plan: &Plan, e: Entity) -> Option<Entity> {
    match e {
        Entity::Machining(id) => mf(plan, id).map(|f| Entity::Stiffness(f.owner)),
        Entity::Operation(id) => plan
            .operations
            .iter()
            .find(|o| o.id == id)
            .map(|o| Entity::Machining(o.feature)),
        Entity::Stiffness(_) | Entity::Setup => Some(Entity::Part),
        Entity::Part => None,
    }
}

pub fn owned(plan: &Plan, e: Entity) -> BTreeSet<Entity> {
    match e {
        Entity::Part => plan
            .stiffness_features
            .iter()
            .map(|f| Entity::Stiffness(f.id))
            .collect(),
        Entity::Stiffness(id) => plan
            .machining_features
            .iter()
            .filter(|f| f.owner == id)
            .map(|f| Entity::Machining(f.id))
            .collect(),
        Entity::Machining(id) => plan
            .operations
            .iter()
            .filter(|o| o.feature == id)
            .map(|o| Entity::Operation(o.id))
            .collect(),
        _ => BTreeSet::new(),
    }
}

/// The machining features in an order honouring `machining_constraints`
/// ([`Plan::machining_order`]).
pub fn machining_order(plan: &Plan) -> Vec<MachiningFeatureId> {
    plan.machining_order()
}

/// The modelled deflection of the wall while one of its machining features
/// is cut: the sizing model's stepped cantilever (§4.1.2) loaded by the
/// knowledge's milling force at the bottom of the cut, with the wall's
/// thickness at each depth as the in-process stock leaves it (features
/// machined so far, the one being cut included, are gone).
#[derive(Debug, Clone, PartialEq)]
pub struct DeflectionReadout {
    pub wall: StiffnessFeatureId,
    /// δ_E, mm.
    pub deflection: f64,
    /// The knowledge's allowed deflection, mm.
    pub allowed: f64,
    /// What the determine stage's sizing computed for the worst state, mm.
    pub planned: Option<f64>,
    pub mode: MillingMode,
}

impl DeflectionReadout {
    pub fn too_large(&self) -> bool {
        // NaN (a model that cannot say) counts as too large.
        self.deflection.is_nan() || self.deflection > self.allowed
    }
}

/// The deflection of the owner wall of `order[step]` with `order[..=step]`
/// removed; `None` when the feature is no wall step (no depth values) or
/// the wall lacks a thickness.
pub fn deflection_at(
    plan: &Plan,
    k: &Knowledge,
    order: &[MachiningFeatureId],
    step: usize,
) -> Option<DeflectionReadout> {
    let cur = mf(plan, *order.get(step)?)?;
    let wall = sf(plan, cur.owner)?;
    let t = wall.thickness?;
    let v = &cur.provenance.values;
    let depth_to = *v.get("depth_to")?;
    let height = wall.height;
    let material = k.material(&plan.setup.material)?;
    let mode = milling_mode(k, &cur.provenance.rule);
    let removed: BTreeSet<MachiningFeatureId> = order[..=step].iter().copied().collect();
    // The wall's features with the depths and width they cover.
    let bands: Vec<(f64, f64, f64, bool)> = plan
        .machining_features
        .iter()
        .filter(|f| f.owner == cur.owner)
        .filter_map(|f| {
            let v = &f.provenance.values;
            Some((
                *v.get("depth_from")?,
                *v.get("depth_to")?,
                *v.get("width")?,
                removed.contains(&f.id),
            ))
        })
        .collect();
    let mut cuts: Vec<f64> = vec![depth_to, height];
    for b in &bands {
        for d in [b.0, b.1] {
            if d > depth_to && d < height {
                cuts.push(d);
            }
        }
    }
    cuts.sort_by(f64::total_cmp);
    cuts.dedup_by(|a, b| (*a - *b).abs() < 1e-9);
    let sk = &k.sizing;
    let le = wall.length.min(sk.effective_length_factor * height);
    let e = material.youngs_modulus;
    let pieces: Vec<Piece> = cuts
        .windows(2)
        .map(|w| {
            let mid = 0.5 * (w[0] + w[1]);
            let stock: f64 = bands
                .iter()
                .filter(|b| !b.3 && b.0 <= mid && mid <= b.1)
                .map(|b| b.2)
                .sum();
            let s = t + stock;
            Piece {
                from: w[0] - depth_to,
                to: w[1] - depth_to,
                ei: e * le * s.powi(3) / 12.0,
            }
        })
        .collect();
    let (delta_d, theta_d) = thinplan_sizing::stepped_cantilever(sk.max_milling_force, &pieces);
    let d = CutSizes::new(sk, mode).danger_zone;
    Some(DeflectionReadout {
        wall: cur.owner,
        deflection: delta_d + theta_d * d,
        allowed: sk.allowed_deflection,
        planned: v.get("deflection").copied(),
        mode,
    })
}

/// The milling mode of the knowledge block that made a feature.
fn milling_mode(k: &Knowledge, rule: &str) -> MillingMode {
    let id = rule.strip_prefix("strategies.").unwrap_or(rule);
    for s in &k.strategies.strategies {
        for b in &s.blocks {
            if let Block::WallSteps(w) = b {
                if w.id == id {
                    return match w.mode {
                        thinplan_knowledge::StrategyMillingMode::Face => MillingMode::Face,
                        thinplan_knowledge::StrategyMillingMode::Peripheral => {
                            MillingMode::Peripheral
                        }
                    };
                }
            }
        }
    }
    MillingMode::Peripheral
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::BTreeMap;

    #[test]
    fn order_follows_constraints_then_ids() {
        let k = thinplan_pipeline::load_knowledge(None).unwrap();
        let setup =
            thinplan_pipeline::make_setup(&thinplan_pipeline::SetupRequest::default(), &k).unwrap();
        let mut s = thinplan_pipeline::Session::open("builtin:tall_rib", setup, k).unwrap();
        s.run_all(|_| {}).unwrap();
        let order = machining_order(&s.plan);
        assert_eq!(order.len(), s.plan.machining_features.len());
        let pos: BTreeMap<_, _> = order.iter().enumerate().map(|(i, id)| (*id, i)).collect();
        for c in &s.plan.machining_constraints {
            if c.kind == ConstraintKind::Before {
                assert!(
                    pos[&c.first] < pos[&c.second],
                    "{} before {}",
                    c.first,
                    c.second
                );
            }
        }
        // Every wall step has a finite read-out.
        let mut n = 0;
        for i in 0..order.len() {
            if let Some(r) = deflection_at(&s.plan, &s.knowledge, &order, i) {
                assert!(r.deflection.is_finite() && r.deflection >= 0.0);
                n += 1;
            }
        }
        assert!(n > 0);
        // Lookups find every feature, in id order or shuffled.
        let mut p = s.plan.clone();
        for f in &s.plan.machining_features {
            assert_eq!(mf(&p, f.id), Some(f));
        }
        p.machining_features.reverse();
        p.stiffness_features.reverse();
        for f in &s.plan.machining_features {
            assert_eq!(mf(&p, f.id), Some(f));
        }
        for f in &s.plan.stiffness_features {
            assert_eq!(sf(&p, f.id), Some(f));
        }
        assert!(mf(&p, MachiningFeatureId(u32::MAX)).is_none());
    }
}
