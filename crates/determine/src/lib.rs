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
//! - `ConnectedWalls`, `Cutouts`, `LargeHoles`, `Details` (figures
//!   4.6–4.8, 4.10) are read before `WallSteps`, which effectuates them
//!   once the wall is sized: step boundaries (the step separation line),
//!   zones with other sizes, a width cap and depression or detail features
//!   inserted in the wall's sequence (module `influence`);
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
    Adjacency, Constraint, ConstraintKind, FeatureOrigin, MachiningFeature, MachiningFeatureId,
    Plan, Prism, PrismFrame, ProfileLoop, ProfileVertex, Provenance, ProvenanceSource, Refusal,
    Region, Stage, StiffnessFeature, StiffnessFeatureId, StiffnessKind, WallRole,
};
use thinplan_sizing::{MillingMode, SizingError, StepSizes, Wall};

mod geom;
mod influence;
pub use geom::{area2, clip, flatten, prism_points, span};
use influence::{Effects, Placement, Sz};

/// The prefix of the provenance rule of everything this stage makes.
pub const RULE_PREFIX: &str = "strategies.";
/// The provenance rule of constraints carried over from stiffness constraints.
pub const RULE_CARRIED: &str = "strategies.carried";

/// The provenance rule of a carried constraint's exception: a feature of the
/// second stiffness feature that would stand beside a shank goes first.
pub const RULE_CARRIED_SHANK: &str = "strategies.carried_shank_access";

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
    carry_over(plan, k, &chains, &mut out);
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
    // Influence blocks read so far, effectuated by the next wall steps.
    let mut influences: Vec<&Block> = Vec::new();
    for block in &strategy.blocks {
        match block {
            Block::SideChoice(b) => side = Some(choose_side(ctx, sf, &g, b)),
            Block::ConnectedWalls(_)
            | Block::Cutouts(_)
            | Block::LargeHoles(_)
            | Block::Details(_) => influences.push(block),
            Block::WallSteps(b) => {
                let side = side.clone().unwrap_or((1.0, "no side choice block".into()));
                chain.extend(wall_steps(ctx, sf, &g, b, side, &influences, out));
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
    /// The same direction in 3D (zero for a wall lying flat).
    hup: DVec3,
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
        let (hdir, hup) = if w.length() > 1e-9 {
            let w = w.normalize();
            (DVec2::new(fx.dot(w), fy.dot(w)), w)
        } else {
            (DVec2::ZERO, DVec3::ZERO)
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
            hup,
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
    /// This band's sizes (the wall's, or an influence's zone).
    sz: Sz,
    /// Why the sizes differ from the wall's (empty when they do not).
    why: String,
}

/// The step approach for one rib or flange (§4.1.1, figure 4.1).
fn wall_steps(
    ctx: &Ctx,
    sf: &StiffnessFeature,
    g: &WallGeom,
    b: &WallSteps,
    (side_a, why): (f64, String),
    influences: &[&Block],
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
    let wall_sz = Sz {
        b_rf: sizes.b_rf,
        h: sizes.h,
        big_h: sizes.big_h,
    };
    // Accept the connected features' influences, in the strategy's order.
    let mut eff = Effects::default();
    for inf in influences {
        match inf {
            Block::ConnectedWalls(c) => influence::connected_walls(ctx, sf, c, wall_sz, &mut eff),
            Block::Cutouts(c) => influence::cutouts(ctx, sf, g, c, wall_sz, b.mode, &mut eff),
            Block::LargeHoles(c) => influence::large_holes(ctx, sf, g, c, wall_sz, &mut eff),
            Block::Details(c) => influence::details(ctx, sf, g, c, wall_sz, &mut eff),
            _ => {}
        }
    }
    out.warnings.append(&mut eff.warnings);
    let room_on = |s: f64| {
        if b.clip_to_blank {
            g.room(ctx.blank, s)
        } else {
            f64::INFINITY
        }
    };
    let has = |s: f64| room_on(s) >= b.min_side_width.max(EPS);
    let (ha, hb) = (has(side_a), has(-side_a));
    for (s, h) in [(side_a, ha), (-side_a, hb)] {
        let w = room_on(s);
        if h && w < sizes.b_rf * b.width_in_b_rf - EPS {
            out.warnings.push(format!(
                "{}: features on the {} side cut back to {w:.2} mm by the blank (B_RF = {})",
                sf.id,
                if s > 0.0 { "+normal" } else { "−normal" },
                sizes.b_rf
            ));
        }
    }
    if !ha && !hb {
        out.warnings.push(format!(
            "{}: no material beside the wall; nothing to step",
            sf.id
        ));
        return Vec::new();
    }
    if ha != hb {
        out.warnings.push(format!(
            "{}: material on one side only; machined one-sided in steps of h = {}",
            sf.id, sizes.h
        ));
    }
    // Segments between the boundaries the influences ask for (the step
    // separation line, a cut-out zone's bottom), each stepped from its top.
    let mut cuts: Vec<f64> = eff
        .breaks
        .iter()
        .map(|b| b.at)
        .filter(|h| *h > g.foot + EPS && *h < g.top - EPS)
        .collect();
    cuts.extend([g.top, g.foot]);
    cuts.sort_by(|a, b| b.total_cmp(a));
    cuts.dedup_by(|a, b| (*a - *b).abs() < EPS);
    let bands = |lo: f64, hi: f64, step: f64| -> Vec<(f64, f64)> {
        let n = (((hi - lo) / step) - 1e-9).ceil().max(1.0) as usize;
        (0..n)
            .map(|i| {
                let top = hi - step * i as f64;
                let bot = (hi - step * (i + 1) as f64).max(lo);
                (bot, top)
            })
            .collect()
    };
    let mut steps: Vec<Step> = Vec::new();
    for seg in cuts.windows(2) {
        let (hi, lo) = (seg[0], seg[1]);
        let mut sz = wall_sz;
        let mut why = Vec::new();
        for z in &eff.zones {
            if lo >= z.lo - EPS && hi <= z.hi + EPS {
                sz.h = sz.h.min(z.sizes.h);
                sz.big_h = sz.big_h.min(z.sizes.big_h);
                sz.b_rf = sz.b_rf.max(z.sizes.b_rf);
                why.push(z.why.clone());
            }
        }
        let why = why.join("; ");
        let mk = |side: f64, large: bool, (lo, hi): (f64, f64)| Step {
            side,
            large,
            lo,
            hi,
            sz,
            why: why.clone(),
        };
        if ha && hb {
            let small = bands(lo, hi, sz.h);
            let mut next_small = 0;
            for band in bands(lo, hi, sz.big_h) {
                steps.push(mk(side_a, true, band));
                // The small features this large one has exposed the far side of.
                while next_small < small.len() && small[next_small].0 >= band.0 - EPS {
                    steps.push(mk(-side_a, false, small[next_small]));
                    next_small += 1;
                }
            }
        } else {
            let s = if ha { side_a } else { -side_a };
            for band in bands(lo, hi, sz.h) {
                steps.push(mk(s, false, band));
            }
        }
    }
    // Where each inserted depression feature goes: after which step (none:
    // before the first).
    let after: Vec<Option<usize>> = eff
        .inserts
        .iter()
        .map(|ins| {
            let last = steps.len().saturating_sub(1);
            let exposed = steps
                .iter()
                .position(|s| s.lo <= ins.lo + EPS)
                .unwrap_or(last);
            match ins.placement {
                Placement::Exposed => Some(exposed),
                Placement::Last => Some(
                    steps
                        .iter()
                        .rposition(|s| s.lo < ins.hi - EPS && s.hi > ins.lo + EPS)
                        .unwrap_or(exposed),
                ),
                Placement::First => None,
            }
        })
        .collect();
    let break_values: Vec<(&str, f64)> = eff
        .breaks
        .iter()
        .flat_map(|b| b.values.iter().copied())
        .collect();
    let (n_large, n_small) = (
        steps.iter().filter(|s| s.large).count(),
        steps.iter().filter(|s| !s.large).count(),
    );
    let mut chain = Vec::new();
    // Inserted features waiting for the wall's next step.
    let mut pending: Vec<(MachiningFeatureId, Provenance)> = Vec::new();
    let (mut i_large, mut i_small) = (0, 0);
    insert_due(ctx, sf, g, &eff, &after, None, &chain, &mut pending, out);
    for (i, st) in steps.iter().enumerate() {
        // The model's deflection for the sizes this step uses (an influence
        // may have changed them from the wall's own).
        let step_sizes = thinplan_sizing::Sizes {
            b_rf: st.sz.b_rf,
            h: st.sz.h,
            big_h: st.sz.big_h,
        };
        let delta =
            thinplan_sizing::deflection(&wall, &step_sizes, &ctx.k.sizing, ctx.e_modulus, mode);
        let values = |mut p: Provenance| {
            p = p
                .with_value("b_rf", st.sz.b_rf)
                .with_value("h", st.sz.h)
                .with_value("big_h", st.sz.big_h)
                .with_value("deflection", delta)
                .with_value("allowed_deflection", ctx.k.sizing.allowed_deflection);
            for (k, v) in &break_values {
                p = p.with_value(*k, *v);
            }
            p
        };
        let mut w = (st.sz.b_rf * b.width_in_b_rf).min(room_on(st.side));
        let mut capped = Vec::new();
        for cap in &eff.width_caps {
            if (!cap.local || st.lo <= g.foot + EPS) && cap.cap < w {
                w = cap.cap;
                capped.push(cap);
            }
        }
        if let Some((shape, side_adjacency)) = g.prism(st.lo, st.hi, st.side, w) {
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
            // The web's permissible height, binding or not, for explanations.
            for cap in &eff.width_caps {
                for (k, v) in &cap.values {
                    prov = prov.with_value(*k, *v);
                }
            }
            prov.note = format!(
                "{}: {kind} feature {num} of {of} on side {} ({}normal), depth {:.3}–{:.3} mm; \
                 side A by {why}",
                sf.id,
                if st.side == side_a { "A" } else { "B" },
                if st.side > 0.0 { "+" } else { "−" },
                g.top - st.hi,
                g.top - st.lo
            );
            if !st.why.is_empty() {
                prov.note.push_str(&format!("; sizes: {}", st.why));
            }
            for cap in &capped {
                prov.note
                    .push_str(&format!("; {} ({})", cap.note, cap.rule));
            }
            out.features.push(MachiningFeature {
                id,
                owner: sf.id,
                shape,
                side_adjacency,
                hole_adjacency: Vec::new(),
                bottom_adjacency: Adjacency::Product,
                origin: FeatureOrigin {
                    rule: rule.clone(),
                    large: Some(st.large),
                },
                access_blocked: false,
                slopes: None,
                provenance: prov,
            });
            for (p, mut cp) in pending.drain(..) {
                cp.note = format!("{cp_note} before the wall's next step", cp_note = cp.note);
                out.constraints.push(Constraint {
                    first: p,
                    second: id,
                    kind: ConstraintKind::Before,
                    priority: 0,
                    provenance: cp,
                });
            }
            let mut p = values(Provenance::new(ProvenanceSource::Knowledge, rule.clone()));
            p.note = format!("{}: figure 4.1 order, alternating sides top-down", sf.id);
            extend_chain(out, &mut chain, id, p);
        }
        // The depression features this step makes due.
        insert_due(ctx, sf, g, &eff, &after, Some(i), &chain, &mut pending, out);
    }
    chain
}

/// Makes the inserted depression and detail features due after step `due`
/// (`None`: before the wall's first step): each after the wall's chain so
/// far and, through `pending`, before the wall's next step.
#[allow(clippy::too_many_arguments)]
fn insert_due(
    ctx: &Ctx,
    sf: &StiffnessFeature,
    g: &WallGeom,
    eff: &Effects,
    after: &[Option<usize>],
    due: Option<usize>,
    chain: &[MachiningFeatureId],
    pending: &mut Vec<(MachiningFeatureId, Provenance)>,
    out: &mut Determination,
) {
    for (ins, _) in eff.inserts.iter().zip(after).filter(|(_, a)| **a == due) {
        let Some((shape, side_adjacency)) =
            influence::piece(g, &ins.shape, ins.lo, ins.hi, ins.open_at)
        else {
            out.warnings.push(format!(
                "{}: its piece at depth {:.2}–{:.2} mm of {} is empty; not made",
                ins.owner,
                g.top - ins.hi,
                g.top - ins.lo,
                sf.id
            ));
            continue;
        };
        let id = MachiningFeatureId(out.features.len() as u32);
        let mut prov = Provenance::new(ProvenanceSource::Knowledge, ins.rule.clone());
        for (k, v) in &ins.values {
            prov = prov.with_value(*k, *v);
        }
        prov = prov
            .with_value("wall", f64::from(sf.id.0))
            .with_value("depth_from", g.top - ins.hi)
            .with_value("depth_to", g.top - ins.lo)
            .with_value("access_x", ctx.up.x)
            .with_value("access_y", ctx.up.y)
            .with_value("access_z", ctx.up.z);
        let mut cp = prov.clone();
        prov.note = ins.note.clone();
        out.features.push(MachiningFeature {
            id,
            owner: ins.owner,
            shape,
            side_adjacency,
            hole_adjacency: Vec::new(),
            bottom_adjacency: Adjacency::Open,
            origin: FeatureOrigin {
                rule: ins.rule.clone(),
                large: ins
                    .values
                    .iter()
                    .find(|(k, _)| *k == "large")
                    .map(|(_, v)| *v > 0.5),
            },
            access_blocked: false,
            slopes: None,
            provenance: prov,
        });
        cp.note = format!(
            "{}: {} piece of {}, {}",
            ins.owner,
            match ins.placement {
                Placement::Exposed => "as soon as exposed",
                Placement::Last => "after the wall beside it",
                Placement::First => "before all of the wall's features",
            },
            sf.id,
            "inserted in the wall's steps"
        );
        if let Some(&prev) = chain.last() {
            out.constraints.push(Constraint {
                first: prev,
                second: id,
                kind: ConstraintKind::Before,
                priority: 0,
                provenance: cp.clone(),
            });
        }
        pending.push((id, cp));
    }
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

/// Stiffness constraints carried over to the owners' machining features:
/// the last feature of the first before the first of the second. With the
/// knowledge's `shank_access`, the order gives way where it would have a
/// shank rub (`yield_to_shanks`).
fn carry_over(
    plan: &Plan,
    k: &Knowledge,
    chains: &[(StiffnessFeatureId, Vec<MachiningFeatureId>)],
    out: &mut Determination,
) {
    let chain_of = |id: StiffnessFeatureId| {
        chains
            .iter()
            .find(|(o, _)| *o == id)
            .map(|(_, c)| c.as_slice())
    };
    let shank = if k.interference.shank_access {
        k.tool_set(&plan.setup.tool_set)
            .and_then(|t| t.reach_and_rise())
    } else {
        None
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
                let carried = Constraint {
                    first: *a.last().expect("chains are not empty"),
                    second: b[0],
                    kind: ConstraintKind::Before,
                    priority: c.priority,
                    provenance: p,
                };
                let yielded = shank.and_then(|(reach, rise)| {
                    yield_to_shanks(out, plan.setup.up, a, b, c, reach, rise)
                });
                match yielded {
                    Some(edges) => out.constraints.extend(edges),
                    None => out.constraints.push(carried),
                }
            }
            ConstraintKind::Simultaneous => out.warnings.push(format!(
                "{} simultaneous with {} ({}): interleaving their machining features is not \
                 built yet; left to the order stage",
                c.first, c.second, c.provenance.rule
            )),
        }
    }
}

/// Where the first stiffness feature's machining feature `a_i` would be cut
/// with the second's leading features `b_0..=b_j` still standing beside it
/// higher than the shortest flute above its bottom (within the set's
/// reach), a shank would rub them: those come before `a_i`, and the rest of
/// the second after the whole first, so that the step approach interleaves
/// with the layers above instead of the whole first going before the whole
/// second (thesis figure 4.6: the order applied locally where it would
/// hurt). `None` where no shank would rub, or where the interleaving would
/// close a cycle with the constraints so far (recorded as a warning).
fn yield_to_shanks(
    out: &mut Determination,
    up: DVec3,
    a: &[MachiningFeatureId],
    b: &[MachiningFeatureId],
    c: &Constraint<StiffnessFeatureId>,
    reach: f64,
    rise: f64,
) -> Option<Vec<Constraint<MachiningFeatureId>>> {
    let feature = |id: MachiningFeatureId| &out.features[id.0 as usize];
    let up = up.normalize_or_zero();
    let (ext_a, ext_b): (Vec<Extent>, Vec<Extent>) = (
        a.iter().map(|&id| Extent::of(feature(id), up)).collect(),
        b.iter().map(|&id| Extent::of(feature(id), up)).collect(),
    );
    let needs: Vec<usize> = ext_a
        .iter()
        .map(|ea| {
            ext_b
                .iter()
                .rposition(|eb| ea.shank_neighbour(eb, reach, rise))
                .map_or(0, |j| j + 1)
        })
        .collect();
    let most = *needs.iter().max()?;
    if most == 0 {
        return None;
    }
    let mut edges = Vec::new();
    for (i, (&ai, &need)) in a
        .iter()
        .zip(&needs)
        .enumerate()
        .filter(|(_, (_, n))| **n > 0)
    {
        let bj = b[need - 1];
        let (fa, fb) = (&ext_a[i], &ext_b[need - 1]);
        let mut p = Provenance::new(ProvenanceSource::Knowledge, RULE_CARRIED_SHANK)
            .with_value("first", f64::from(c.first.0))
            .with_value("second", f64::from(c.second.0))
            .with_value("flute_length", rise)
            .with_value("reach", reach)
            .with_value("top_of_first", fb.hi)
            .with_value("bottom_of_second", fa.lo);
        p.note = format!(
            "{} before {} ({}) gives way: {bj} stands {:.2} mm above {ai}'s bottom within Ø{reach} \
             of it, higher than the shortest flute {rise}: a shank cutting {ai} would rub it",
            c.first,
            c.second,
            c.provenance.rule,
            fb.hi - fa.lo
        );
        edges.push(Constraint {
            first: bj,
            second: ai,
            kind: ConstraintKind::Before,
            priority: c.priority,
            provenance: p,
        });
    }
    // Every feature of the second still follows the first's features that
    // do not need it gone: the two chains interleave top-down.
    for (j, &bj) in b.iter().enumerate().take(most) {
        let i0 = needs.iter().position(|&n| n > j).unwrap_or(a.len());
        let starts_group = j == 0 || needs.iter().position(|&n| n > j - 1).unwrap_or(a.len()) != i0;
        if i0 == 0 || !starts_group {
            continue;
        }
        let mut p = Provenance::new(ProvenanceSource::Knowledge, RULE_CARRIED)
            .with_value("first", f64::from(c.first.0))
            .with_value("second", f64::from(c.second.0));
        p.note = format!(
            "{} before {} ({}): {} before {bj}, which goes early for a shank ({RULE_CARRIED_SHANK})",
            c.first,
            c.second,
            c.provenance.rule,
            a[i0 - 1]
        );
        edges.push(Constraint {
            first: a[i0 - 1],
            second: bj,
            kind: ConstraintKind::Before,
            priority: c.priority,
            provenance: p,
        });
    }
    if let (Some(&last), Some(&rest)) = (a.last(), b.get(most)) {
        let mut p = Provenance::new(ProvenanceSource::Knowledge, RULE_CARRIED)
            .with_value("first", f64::from(c.first.0))
            .with_value("second", f64::from(c.second.0))
            .with_value("standing_first", most as f64);
        p.note = format!(
            "{} before {} ({}): the last feature of the first before the second's features below \
             the shank's reach ({most} of the second's come earlier: {RULE_CARRIED_SHANK})",
            c.first, c.second, c.provenance.rule
        );
        edges.push(Constraint {
            first: last,
            second: rest,
            kind: ConstraintKind::Before,
            priority: c.priority,
            provenance: p,
        });
    }
    if closes_cycle(out.features.len(), &out.constraints, &edges) {
        out.warnings.push(format!(
            "{} before {} ({}): a shank would rub the second's upper features, but letting them \
             go first would close a cycle; the whole first goes before the second",
            c.first, c.second, c.provenance.rule
        ));
        return None;
    }
    Some(edges)
}

/// A stage-5 feature's extent in the set-up: along the up axis, and its
/// box in the plane across it. Stage 5's wall features are prisms in their
/// wall's frame, so the plan-view comparison of later stages does not apply.
struct Extent {
    lo: f64,
    hi: f64,
    across: [f64; 4],
}

impl Extent {
    fn of(f: &MachiningFeature, up: DVec3) -> Self {
        let (e1, e2) = up.any_orthonormal_pair();
        let fr = &f.shape.frame;
        let y = fr.z.cross(fr.x);
        let mut e = Extent {
            lo: f64::INFINITY,
            hi: f64::NEG_INFINITY,
            across: [
                f64::INFINITY,
                f64::INFINITY,
                f64::NEG_INFINITY,
                f64::NEG_INFINITY,
            ],
        };
        for v in &f.shape.region.outer.vertices {
            for z in [f.shape.z_min, f.shape.z_max] {
                let p = fr.origin + fr.x * v.x + y * v.y + fr.z * z;
                let (h, u, w) = (p.dot(up), p.dot(e1), p.dot(e2));
                e.lo = e.lo.min(h);
                e.hi = e.hi.max(h);
                e.across = [
                    e.across[0].min(u),
                    e.across[1].min(w),
                    e.across[2].max(u),
                    e.across[3].max(w),
                ];
            }
        }
        e
    }

    /// As `MachiningFeature::shank_neighbour`: `g` within `margin` across
    /// and higher than `rise` above this one's bottom.
    fn shank_neighbour(&self, g: &Extent, margin: f64, rise: f64) -> bool {
        let (a, b) = (self.across, g.across);
        g.hi > self.lo + rise
            && b[0] <= a[2] + margin
            && a[0] <= b[2] + margin
            && b[1] <= a[3] + margin
            && a[1] <= b[3] + margin
    }
}

/// Whether `existing` plus `added` (`Before` constraints between `n`
/// features) has a cycle.
fn closes_cycle(
    n: usize,
    existing: &[Constraint<MachiningFeatureId>],
    added: &[Constraint<MachiningFeatureId>],
) -> bool {
    let edges = existing
        .iter()
        .chain(added)
        .filter(|c| c.kind == ConstraintKind::Before)
        .map(|c| (c.first.0 as usize, c.second.0 as usize));
    thinplan_plan::topological_order(n, edges).len() < n
}

pub mod web;
