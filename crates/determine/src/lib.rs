//! Stage 5, determine: machining features (removal volumes owned by a
//! stiffness feature) and their sequence constraints, from the stiffness
//! features, the strategies of `knowledge/strategies.ron` and the sizing
//! model (thesis §4.1, figures 4.1 and 4.13).
//!
//! For each stiffness feature, in id order, the strategy for its role runs
//! its blocks in order:
//!
//! - `SideChoice` (§4.1.3 rules 1–2) decides side A, the side of the large
//!   features;
//! - `WallSteps` (§4.1.1, figure 4.1) sizes a rib or flange with
//!   [`thinplan_sizing::size_wall`] and makes its features: on side A
//!   large ones of height H, on side B small ones of height h, each the
//!   wall's side outline clipped to its height band, swept away from the
//!   wall over `[t/2, t/2 + width]` (width = B_RF · `width_in_b_rf`, cut back
//!   to the blank); they are chained top-down alternating sides: A1, the
//!   small features A1 covers, A2, …;
//! - `WebFaceMill` makes a web's top-down layers (see [`web`]).
//!
//! Each owner's features form one chain of `Before` constraints, so a
//! stiffness constraint `X before Y` carries over as one constraint: the
//! last feature of X before the first of Y. Ids are assigned in that
//! deterministic order. See `README.md` for what is not built yet.

use glam::{DVec2, DVec3};
use thinplan_brep::Brep;
use thinplan_knowledge::{
    Block, Knowledge, SideChoice, SideCriterion, Strategy, StrategyMillingMode, StrategyRole,
    WallSteps,
};
use thinplan_plan::{
    Adjacency, Constraint, ConstraintKind, MachiningFeature, MachiningFeatureId, Plan, Prism,
    PrismFrame, ProfileLoop, ProfileVertex, Provenance, ProvenanceSource, Refusal, Region, Stage,
    StiffnessFeature, StiffnessFeatureId, StiffnessKind, WallRole,
};
use thinplan_sizing::{MillingMode, SizingError, StepSizes, Wall};

mod geom;
pub use geom::{area2, clip, flatten, prism_points, span};

/// The prefix of the provenance rule of everything this stage makes.
pub const RULE_PREFIX: &str = "strategies.";
/// The provenance rule of constraints carried over from stiffness constraints.
pub const RULE_CARRIED: &str = "strategies.carried";

/// Geometric tolerance, mm.
const EPS: f64 = 1e-6;

/// The stage's result.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Determination {
    pub features: Vec<MachiningFeature>,
    pub constraints: Vec<Constraint<MachiningFeatureId>>,
    /// Walls the knowledge could not size, with why.
    pub refusals: Vec<Refusal>,
    /// Things left undone or approximated, for the planner.
    pub warnings: Vec<String>,
}

impl Determination {
    /// Writes the result into a plan: this stage's and later results are
    /// dropped first, then features, constraints and refusals recorded and
    /// the stage listed as done.
    pub fn apply_to(self, plan: &mut Plan) {
        plan.invalidate_from(Stage::Determine);
        plan.machining_features = self.features;
        plan.machining_constraints = self.constraints;
        plan.refusals.extend(self.refusals);
        plan.stages_done.push(Stage::Determine);
    }
}

#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum DetermineError {
    #[error("the plan has not been sequenced yet (stages done: {0:?}); run stage 4 first")]
    NotSequenced(Vec<Stage>),
    #[error("the set-up's material `{0}` is not in the knowledge")]
    UnknownMaterial(String),
    #[error("the set-up's up axis {0} is not a direction")]
    BadUp(DVec3),
}

/// Runs stage 5 on a sequenced plan; `brep` is the plan's part (for the
/// blank: by default the part's extent).
pub fn determine(plan: &Plan, brep: &Brep, k: &Knowledge) -> Result<Determination, DetermineError> {
    if !plan.stages_done.contains(&Stage::Sequence) {
        return Err(DetermineError::NotSequenced(plan.stages_done.clone()));
    }
    let material = k
        .material(&plan.setup.material)
        .ok_or_else(|| DetermineError::UnknownMaterial(plan.setup.material.clone()))?;
    let up = plan.setup.up;
    if !(up.is_finite() && up.length() > 1e-9) {
        return Err(DetermineError::BadUp(up));
    }
    let up = up.normalize();
    let blank: Vec<DVec3> = brep.vertices.iter().map(|v| v.point).collect();
    let ctx = Ctx {
        plan,
        k,
        e_modulus: material.youngs_modulus,
        up,
        blank: &blank,
    };
    let mut out = Determination::default();
    // Each owner's chain of features, in machining order.
    let mut chains: Vec<(StiffnessFeatureId, Vec<MachiningFeatureId>)> = Vec::new();
    for sf in &plan.stiffness_features {
        let (Some(role), StiffnessKind::Wall) = (sf.role, sf.kind) else {
            continue;
        };
        let srole = match role {
            WallRole::Rib => StrategyRole::Rib,
            WallRole::Flange => StrategyRole::Flange,
            WallRole::Web => StrategyRole::Web,
        };
        let Some(strategy) = k.strategies.for_role(srole) else {
            out.warnings
                .push(format!("{}: no strategy for role {srole:?}", sf.id));
            continue;
        };
        let made = run_strategy(&ctx, sf, strategy, &mut out);
        if !made.is_empty() {
            chains.push((sf.id, made));
        }
    }
    carry_over(plan, &chains, &mut out);
    Ok(out)
}

struct Ctx<'a> {
    plan: &'a Plan,
    k: &'a Knowledge,
    e_modulus: f64,
    up: DVec3,
    blank: &'a [DVec3],
}

/// Runs a strategy's blocks on one wall; returns its features' chain.
fn run_strategy(
    ctx: &Ctx,
    sf: &StiffnessFeature,
    strategy: &Strategy,
    out: &mut Determination,
) -> Vec<MachiningFeatureId> {
    let Some(g) = WallGeom::of(sf, ctx.up) else {
        out.warnings.push(format!(
            "{}: not a planar wall with a side outline; no machining features yet",
            sf.id
        ));
        return Vec::new();
    };
    let mut side: Option<(f64, String)> = None;
    let mut chain = Vec::new();
    for block in &strategy.blocks {
        match block {
            Block::SideChoice(b) => side = Some(choose_side(ctx, sf, &g, b)),
            Block::WallSteps(b) => {
                let side = side.clone().unwrap_or((1.0, "no side choice block".into()));
                chain.extend(wall_steps(ctx, sf, &g, b, side, out));
            }
            Block::WebFaceMill(b) => chain.extend(web::face_mill(ctx, sf, &g, b, out)),
        }
    }
    chain
}

/// A planar wall in its own frame: height along the in-plane up direction.
pub(crate) struct WallGeom {
    origin: DVec3,
    fx: DVec3,
    /// The wall normal (the shape frame's z).
    n: DVec3,
    t: f64,
    /// The side outline (flattened), in the shape frame.
    outline: Vec<DVec2>,
    /// height(p) = hdir · p (2D, shape frame), measured along the in-plane
    /// projection of up; zero for a wall lying flat.
    hdir: DVec2,
    top: f64,
    foot: f64,
}

impl WallGeom {
    fn of(sf: &StiffnessFeature, up: DVec3) -> Option<WallGeom> {
        let shape = sf.shape.as_ref()?;
        let t = sf.thickness?;
        let n = shape.frame.z.normalize_or_zero();
        let fx = shape.frame.x.normalize_or_zero();
        // Planar walls only: the frame's z is the wall normal and the prism
        // spans the thickness.
        if n.dot(sf.axis.normalize_or_zero()).abs() < 1.0 - 1e-6
            || (shape.z_max - shape.z_min - t).abs() > 1e-6 * t.max(1.0)
        {
            return None;
        }
        let fy = n.cross(fx);
        let w = up - n * n.dot(up);
        let hdir = if w.length() > 1e-9 {
            let w = w.normalize();
            DVec2::new(fx.dot(w), fy.dot(w))
        } else {
            DVec2::ZERO
        };
        let outline = flatten(&shape.region.outer);
        if outline.len() < 3 {
            return None;
        }
        let (foot, top) = outline
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
                let h = hdir.dot(*p);
                (lo.min(h), hi.max(h))
            });
        Some(WallGeom {
            origin: shape.frame.origin + n * (0.5 * (shape.z_min + shape.z_max)),
            fx,
            n,
            t,
            outline,
            hdir,
            top,
            foot,
        })
    }

    /// Material between the wall face on side `s` (±1 along the normal) and
    /// the blank boundary, mm.
    fn room(&self, blank: &[DVec3], s: f64) -> f64 {
        let d = self.n * s;
        let (_, hi) = span(blank, d);
        hi - self.origin.dot(d) - 0.5 * self.t
    }

    /// The side outline between heights `lo` and `hi`, as a counter-clockwise
    /// loop in the side frame of side `s` (x kept, y mirrored for s < 0), with
    /// the adjacency of each edge.
    fn band(&self, lo: f64, hi: f64, s: f64) -> Option<(Vec<DVec2>, Vec<Adjacency>)> {
        let p = clip(&self.outline, self.hdir, lo);
        let p = clip(&p, -self.hdir, -hi);
        if p.len() < 3 || area2(&p).abs() < 1e-9 {
            return None;
        }
        let mut p: Vec<DVec2> = p.into_iter().map(|q| DVec2::new(q.x, s * q.y)).collect();
        let hd = DVec2::new(self.hdir.x, s * self.hdir.y);
        if area2(&p) < 0.0 {
            p.reverse();
        }
        let n = p.len();
        let adj = (0..n)
            .map(|i| {
                let (a, b) = (hd.dot(p[i]), hd.dot(p[(i + 1) % n]));
                if (a - lo).abs() < EPS && (b - lo).abs() < EPS {
                    if (lo - self.foot).abs() < EPS {
                        Adjacency::Product
                    } else {
                        Adjacency::Feature
                    }
                } else if (a - hi).abs() < EPS
                    && (b - hi).abs() < EPS
                    && (hi - self.top).abs() > EPS
                {
                    Adjacency::Feature
                } else {
                    Adjacency::Open
                }
            })
            .collect();
        Some((p, adj))
    }

    /// The prism of side `s` over the band `[lo, hi]`, `width` away from the
    /// wall face: frame z = s · normal, z = 0 on the wall face.
    fn prism(&self, lo: f64, hi: f64, s: f64, width: f64) -> Option<(Prism, Vec<Adjacency>)> {
        let (pts, adj) = self.band(lo, hi, s)?;
        let prism = Prism {
            frame: PrismFrame {
                origin: self.origin + self.n * (s * 0.5 * self.t),
                x: self.fx,
                z: self.n * s,
            },
            region: Region {
                outer: ProfileLoop {
                    vertices: pts
                        .iter()
                        .map(|q| ProfileVertex {
                            x: q.x,
                            y: q.y,
                            bulge: 0.0,
                        })
                        .collect(),
                },
                holes: Vec::new(),
            },
            z_min: 0.0,
            z_max: width,
        };
        Some((prism, adj))
    }
}

/// Side A by the block's criteria (§4.1.3 rules 1–2); returns ±1 along
/// the wall normal and a sentence saying why.
fn choose_side(ctx: &Ctx, sf: &StiffnessFeature, g: &WallGeom, b: &SideChoice) -> (f64, String) {
    for c in &b.criteria {
        match c {
            SideCriterion::UpSide { min_cos_to_up } => {
                let c = g.n.dot(ctx.up);
                if c.abs() >= *min_cos_to_up && c.abs() > 1e-9 {
                    return (c.signum(), format!("up side (rule 1, normal·up = {c:.3})"));
                }
            }
            SideCriterion::MostConnected => {
                let (mut plus, mut minus) = (0, 0);
                for con in &ctx.plan.connections {
                    let other = if con.base == sf.id {
                        con.leaf
                    } else if con.leaf == sf.id {
                        con.base
                    } else {
                        continue;
                    };
                    let Some(shape) = ctx
                        .plan
                        .stiffness_features
                        .iter()
                        .find(|f| f.id == other)
                        .and_then(|f| f.shape.as_ref())
                    else {
                        continue;
                    };
                    let (lo, hi) = span(&prism_points(shape), g.n);
                    let o = g.origin.dot(g.n);
                    let half = 0.5 * g.t - 1e-6;
                    if lo - o >= half {
                        plus += 1;
                    } else if hi - o <= -half {
                        minus += 1;
                    }
                }
                if plus != minus {
                    let s = if plus > minus { 1.0 } else { -1.0 };
                    return (
                        s,
                        format!("most connected features (rule 2: {plus} on +normal, {minus} on −normal)"),
                    );
                }
            }
            SideCriterion::MostMaterial { by_more_than } => {
                let (rp, rm) = (g.room(ctx.blank, 1.0), g.room(ctx.blank, -1.0));
                if (rp - rm).abs() > *by_more_than {
                    let s = if rp > rm { 1.0 } else { -1.0 };
                    return (
                        s,
                        format!("most material ({rp:.2} mm on +normal, {rm:.2} mm on −normal)"),
                    );
                }
            }
        }
    }
    (1.0, "no criterion decided: +normal".into())
}

/// One planned feature of a wall before it gets its id.
struct Step {
    side: f64,
    large: bool,
    lo: f64,
    hi: f64,
}

/// The step approach for one rib or flange (§4.1.1, figure 4.1).
fn wall_steps(
    ctx: &Ctx,
    sf: &StiffnessFeature,
    g: &WallGeom,
    b: &WallSteps,
    (side_a, why): (f64, String),
    out: &mut Determination,
) -> Vec<MachiningFeatureId> {
    let rule = format!("{RULE_PREFIX}{}", b.id);
    if g.n.dot(ctx.up).abs() > b.max_cos_to_up || g.hdir == DVec2::ZERO {
        out.warnings.push(format!(
            "{}: too close to horizontal for `{}`; not stepped",
            sf.id, b.id
        ));
        return Vec::new();
    }
    let height = g.top - g.foot;
    let wall = Wall {
        length: sf.length,
        thickness: g.t,
        height,
    };
    let mode = match b.mode {
        StrategyMillingMode::Peripheral => MillingMode::Peripheral,
        StrategyMillingMode::Face => MillingMode::Face,
    };
    let sizes: StepSizes =
        match thinplan_sizing::size_wall(&wall, &ctx.k.sizing, ctx.e_modulus, mode) {
            Ok(s) => s,
            Err(e) => {
                let mut prov = Provenance::new(ProvenanceSource::Knowledge, rule.clone())
                    .with_value("length", wall.length)
                    .with_value("thickness", wall.thickness)
                    .with_value("height", wall.height);
                if let SizingError::Impossible {
                    deflection,
                    allowed,
                    ..
                } = &e
                {
                    prov = prov
                        .with_value("deflection", *deflection)
                        .with_value("allowed_deflection", *allowed);
                }
                prov.note = format!("{}", sf.id);
                out.refusals.push(Refusal {
                    stage: Stage::Determine,
                    rule: rule.clone(),
                    reason: format!("{}: {e}", sf.id),
                    provenance: prov,
                });
                return Vec::new();
            }
        };
    let width = sizes.b_rf * b.width_in_b_rf;
    let width_on = |s: f64| {
        let w = if b.clip_to_blank {
            width.min(g.room(ctx.blank, s))
        } else {
            width
        };
        (w >= b.min_side_width.max(EPS)).then_some(w)
    };
    let (wa, wb) = (width_on(side_a), width_on(-side_a));
    for (s, w) in [(side_a, wa), (-side_a, wb)] {
        if let Some(w) = w {
            if w < width - EPS {
                out.warnings.push(format!(
                    "{}: features on the {} side cut back to {w:.2} mm by the blank (B_RF = {})",
                    sf.id,
                    if s > 0.0 { "+normal" } else { "−normal" },
                    sizes.b_rf
                ));
            }
        }
    }
    // Bands from the top down, depth measured from the top.
    let bands = |step: f64| -> Vec<(f64, f64)> {
        let n = ((height / step) - 1e-9).ceil().max(1.0) as usize;
        (0..n)
            .map(|i| {
                let hi = g.top - step * i as f64;
                let lo = (g.top - step * (i + 1) as f64).max(g.foot);
                (lo, hi)
            })
            .collect()
    };
    let mut steps: Vec<Step> = Vec::new();
    match (wa, wb) {
        (Some(_), Some(_)) => {
            let small = bands(sizes.h);
            let mut next_small = 0;
            for (lo, hi) in bands(sizes.big_h) {
                steps.push(Step {
                    side: side_a,
                    large: true,
                    lo,
                    hi,
                });
                // The small features this large one has exposed the far side of.
                while next_small < small.len() && small[next_small].0 >= lo - EPS {
                    let (l, h) = small[next_small];
                    steps.push(Step {
                        side: -side_a,
                        large: false,
                        lo: l,
                        hi: h,
                    });
                    next_small += 1;
                }
            }
        }
        (Some(_), None) | (None, Some(_)) => {
            let s = if wa.is_some() { side_a } else { -side_a };
            out.warnings.push(format!(
                "{}: material on one side only; machined one-sided in steps of h = {}",
                sf.id, sizes.h
            ));
            for (lo, hi) in bands(sizes.h) {
                steps.push(Step {
                    side: s,
                    large: false,
                    lo,
                    hi,
                });
            }
        }
        (None, None) => {
            out.warnings.push(format!(
                "{}: no material beside the wall; nothing to step",
                sf.id
            ));
            return Vec::new();
        }
    }
    let values = |p: Provenance| {
        p.with_value("b_rf", sizes.b_rf)
            .with_value("h", sizes.h)
            .with_value("big_h", sizes.big_h)
            .with_value("deflection", sizes.deflection)
            .with_value("allowed_deflection", ctx.k.sizing.allowed_deflection)
    };
    let (n_large, n_small) = (
        steps.iter().filter(|s| s.large).count(),
        steps.iter().filter(|s| !s.large).count(),
    );
    let mut chain = Vec::new();
    let (mut i_large, mut i_small) = (0, 0);
    for st in steps {
        let w = if st.side == side_a { wa } else { wb }.expect("side has material");
        let Some((shape, side_adjacency)) = g.prism(st.lo, st.hi, st.side, w) else {
            continue;
        };
        let id = MachiningFeatureId(out.features.len() as u32);
        let (kind, num, of) = if st.large {
            i_large += 1;
            ("large", i_large, n_large)
        } else {
            i_small += 1;
            ("small", i_small, n_small)
        };
        let mut prov = values(Provenance::new(ProvenanceSource::Knowledge, rule.clone()))
            .with_value("side", st.side)
            .with_value("large", if st.large { 1.0 } else { 0.0 })
            .with_value("depth_from", g.top - st.hi)
            .with_value("depth_to", g.top - st.lo)
            .with_value("width", w)
            .with_value("access_x", ctx.up.x)
            .with_value("access_y", ctx.up.y)
            .with_value("access_z", ctx.up.z);
        prov.note = format!(
            "{}: {kind} feature {num} of {of} on side {} ({}normal), depth {:.3}–{:.3} mm; \
             side A by {why}",
            sf.id,
            if st.side == side_a { "A" } else { "B" },
            if st.side > 0.0 { "+" } else { "−" },
            g.top - st.hi,
            g.top - st.lo
        );
        out.features.push(MachiningFeature {
            id,
            owner: sf.id,
            shape,
            side_adjacency,
            hole_adjacency: Vec::new(),
            bottom_adjacency: Adjacency::Product,
            provenance: prov,
        });
        let mut p = values(Provenance::new(ProvenanceSource::Knowledge, rule.clone()));
        p.note = format!("{}: figure 4.1 order, alternating sides top-down", sf.id);
        extend_chain(out, &mut chain, id, p);
    }
    chain
}

/// Appends `id` to a wall's or web's machining order: after the chain's last
/// feature, with `provenance` on the constraint.
fn extend_chain(
    out: &mut Determination,
    chain: &mut Vec<MachiningFeatureId>,
    id: MachiningFeatureId,
    provenance: Provenance,
) {
    if let Some(&prev) = chain.last() {
        out.constraints.push(Constraint {
            first: prev,
            second: id,
            kind: ConstraintKind::Before,
            priority: 0,
            provenance,
        });
    }
    chain.push(id);
}

/// Stiffness constraints carried over to the owners' machining features.
fn carry_over(
    plan: &Plan,
    chains: &[(StiffnessFeatureId, Vec<MachiningFeatureId>)],
    out: &mut Determination,
) {
    let chain_of = |id: StiffnessFeatureId| {
        chains
            .iter()
            .find(|(o, _)| *o == id)
            .map(|(_, c)| c.as_slice())
    };
    for c in &plan.stiffness_constraints {
        let (Some(a), Some(b)) = (chain_of(c.first), chain_of(c.second)) else {
            continue;
        };
        match c.kind {
            ConstraintKind::Before => {
                let mut p = Provenance::new(ProvenanceSource::Knowledge, RULE_CARRIED)
                    .with_value("first", f64::from(c.first.0))
                    .with_value("second", f64::from(c.second.0));
                p.note = format!(
                    "{} before {} ({}): the last feature of the first before the first of the second",
                    c.first, c.second, c.provenance.rule
                );
                out.constraints.push(Constraint {
                    first: *a.last().expect("chains are not empty"),
                    second: b[0],
                    kind: ConstraintKind::Before,
                    priority: c.priority,
                    provenance: p,
                });
            }
            ConstraintKind::Simultaneous => out.warnings.push(format!(
                "{} simultaneous with {} ({}): interleaving their machining features is not \
                 built yet; left to the order stage",
                c.first, c.second, c.provenance.rule
            )),
        }
    }
}

pub mod web;
