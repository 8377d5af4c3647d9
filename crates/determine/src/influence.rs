//! Influences of connected stiffness features on a wall's steps (thesis
//! §4.1.3 "Knowledge examples", figure 4.13): `ConnectedWalls` (figure
//! 4.6), `Cutouts` (figure 4.7) and `LargeHoles` (figure 4.8). Each block is
//! read where it stands in the strategy and effectuated by `WallSteps` once
//! the wall is sized: it adds step boundaries (the step separation line, a
//! cut-out zone's bottom), height zones with other sizes, a cap on the
//! features' width, and depression features to insert in the wall's
//! sequence, each with its placement rule. `Details` (figure 4.10) inserts
//! a chamfer's or fillet's wedge the same way.

use glam::{DVec2, DVec3};
use thinplan_knowledge::{ConnectedWalls, Cutouts, Details, LargeHoles, StrategyMillingMode};
use thinplan_plan::{
    Adjacency, Prism, PrismFrame, ProfileLoop, ProfileVertex, Region, StiffnessFeature,
    StiffnessFeatureId, StiffnessKind, WallRole,
};
use thinplan_sizing::{MillingMode, Wall};

use crate::{area2, clip, flatten, prism_points, Ctx, WallGeom, EPS, RULE_PREFIX};

/// Step sizes (mm).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Sz {
    pub b_rf: f64,
    pub h: f64,
    pub big_h: f64,
}

/// A height band of the wall stepped with other sizes.
pub(crate) struct Zone {
    pub lo: f64,
    pub hi: f64,
    pub sizes: Sz,
    pub why: String,
}

/// When an inserted feature is machined in the wall's sequence.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Placement {
    /// Right after the first wall step that reaches down to its bottom (it
    /// is then exposed on one side): figure 4.7(b), small holes, lower
    /// hole halves.
    Exposed,
    /// After the last wall step (either side) beside it: the upper half of
    /// a large hole (figure 4.8), a large cut-out's pieces.
    Last,
    /// Before all of the wall's features: a large detail (figure 4.10).
    First,
}

/// A depression's machining feature to insert in the wall's sequence: the
/// depression's prism between heights `lo` and `hi` of the wall.
pub(crate) struct Insert {
    pub owner: StiffnessFeatureId,
    pub shape: Prism,
    pub lo: f64,
    pub hi: f64,
    pub placement: Placement,
    pub rule: String,
    pub values: Values,
    pub note: String,
    /// Edges of the piece ending here are `open` (a detail's corner,
    /// outside the part); `None`: every uncut edge is `product`.
    pub open_at: Option<DVec2>,
}

/// A cap on the width of the wall's features (figure 4.6).
pub(crate) struct WidthCap {
    pub cap: f64,
    /// Only the features at the wall's foot.
    pub local: bool,
    pub rule: String,
    pub values: Values,
    pub note: String,
}

/// Provenance values by name.
pub(crate) type Values = Vec<(&'static str, f64)>;

/// A height where a step boundary must fall, with the values that put it
/// there.
pub(crate) struct Break {
    pub at: f64,
    pub values: Values,
}

/// What the influence blocks ask of one wall's steps.
#[derive(Default)]
pub(crate) struct Effects {
    pub breaks: Vec<Break>,
    pub zones: Vec<Zone>,
    pub inserts: Vec<Insert>,
    pub width_caps: Vec<WidthCap>,
    pub warnings: Vec<String>,
}

/// A depression in the wall: its feature, prism and extent.
struct Dep<'a> {
    sf: &'a StiffnessFeature,
    shape: &'a Prism,
    lo: f64,
    hi: f64,
    x0: f64,
    x1: f64,
}

impl WallGeom {
    /// Height of a point along the wall's in-plane up direction, in the
    /// wall's own measure (`top`, `foot`).
    pub(crate) fn height_of(&self, p: DVec3) -> f64 {
        self.hup.dot(p - self.origin)
    }

    /// Position of a point along the wall (its frame x).
    fn along(&self, p: DVec3) -> f64 {
        self.fx.dot(p - self.origin)
    }

    /// The wall's extent along its frame x.
    fn x_range(&self) -> (f64, f64) {
        self.outline
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
                (lo.min(p.x), hi.max(p.x))
            })
    }
}

/// The depressions of `kind` connected to the wall and through it (axis
/// along the wall normal), or the details of `kind` on it (wedge in the
/// wall's frame), by stiffness-feature id.
fn depressions<'a>(
    ctx: &Ctx<'a>,
    sf: &StiffnessFeature,
    g: &WallGeom,
    kind: StiffnessKind,
) -> Vec<Dep<'a>> {
    let mut out: Vec<Dep<'a>> = Vec::new();
    for con in &ctx.plan.connections {
        let other = if con.base == sf.id {
            con.leaf
        } else if con.leaf == sf.id {
            con.base
        } else {
            continue;
        };
        let Some(d) = ctx
            .plan
            .stiffness_features
            .iter()
            .find(|f| f.id == other && f.kind == kind)
        else {
            continue;
        };
        let Some(shape) = d.shape.as_ref() else {
            continue;
        };
        // A depression goes through the wall (its axis along the normal);
        // a detail's wedge lies in the wall's slab (its frame z the normal).
        let along = if matches!(kind, StiffnessKind::Chamfer | StiffnessKind::Fillet) {
            shape.frame.z
        } else {
            d.axis
        };
        if along.normalize_or_zero().dot(g.n).abs() < 0.9 || out.iter().any(|o| o.sf.id == d.id) {
            continue;
        }
        let pts = prism_points(shape);
        let (mut lo, mut hi, mut x0, mut x1) = (
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
        );
        for p in &pts {
            let (h, x) = (g.height_of(*p), g.along(*p));
            lo = lo.min(h);
            hi = hi.max(h);
            x0 = x0.min(x);
            x1 = x1.max(x);
        }
        if pts.is_empty() {
            continue;
        }
        out.push(Dep {
            sf: d,
            shape,
            lo,
            hi,
            x0,
            x1,
        });
    }
    out.sort_by_key(|d| d.sf.id);
    out
}

/// The part of a depression's prism between wall heights `lo` and `hi`, in
/// the depression's own frame (z: its axis), with the adjacency of each
/// edge: `feature` on a cut line (the rest of the depression), `product`
/// elsewhere (the depression's own boundary).
pub(crate) fn piece(
    g: &WallGeom,
    shape: &Prism,
    lo: f64,
    hi: f64,
    open_at: Option<DVec2>,
) -> Option<(Prism, Vec<Adjacency>)> {
    let fx = shape.frame.x.normalize_or_zero();
    let fz = shape.frame.z.normalize_or_zero();
    let fy = fz.cross(fx);
    let c = g.height_of(shape.frame.origin);
    let d2 = DVec2::new(g.hup.dot(fx), g.hup.dot(fy));
    if d2.length() < 1e-9 {
        return None;
    }
    let p = clip(&flatten(&shape.region.outer), d2, lo - c);
    let mut p = clip(&p, -d2, c - hi);
    if p.len() < 3 || area2(&p).abs() < 1e-9 {
        return None;
    }
    if area2(&p) < 0.0 {
        p.reverse();
    }
    let n = p.len();
    let on = |q: DVec2, at: f64| (d2.dot(q) + c - at).abs() < 1e-6;
    let adj = (0..n)
        .map(|i| {
            let (a, b) = (p[i], p[(i + 1) % n]);
            if (on(a, lo) && on(b, lo)) || (on(a, hi) && on(b, hi)) {
                Adjacency::Feature
            } else if open_at.is_some_and(|c| a.distance(c) < 1e-6 || b.distance(c) < 1e-6) {
                Adjacency::Open
            } else {
                Adjacency::Product
            }
        })
        .collect();
    let prism = Prism {
        frame: PrismFrame {
            origin: shape.frame.origin,
            x: fx,
            z: fz,
        },
        region: Region {
            outer: ProfileLoop {
                vertices: p
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
        z_min: shape.z_min,
        z_max: shape.z_max,
    };
    Some((prism, adj))
}

/// Figure 4.8: the holes through the wall.
pub(crate) fn large_holes(
    ctx: &Ctx,
    sf: &StiffnessFeature,
    g: &WallGeom,
    b: &LargeHoles,
    sizes: Sz,
    eff: &mut Effects,
) {
    let rule = format!("{RULE_PREFIX}{}", b.id);
    let d_tool = ctx.k.sizing.preferred_tool_diameter;
    let holes = depressions(ctx, sf, g, StiffnessKind::Hole);
    let large_above = b.large_above_tool_diameters * d_tool;
    let is_large = |d: &Dep| d.hi - d.lo > large_above;
    // One line for the whole row: below the top of the highest large hole.
    let highest = holes
        .iter()
        .filter(|d| is_large(d))
        .map(|d| d.hi.min(g.top))
        .fold(f64::NEG_INFINITY, f64::max);
    let sep = highest - b.separation_in_tool_diameters * d_tool;
    let line = highest.is_finite() && sep > g.foot + EPS && sep < g.top - EPS;
    if line {
        eff.breaks.push(Break {
            at: sep,
            values: vec![
                ("separation_height", sep - g.foot),
                ("separation_depth", g.top - sep),
                ("tool_diameter", d_tool),
            ],
        });
    }
    for d in &holes {
        let diameter = d.sf.diameter.unwrap_or(d.hi - d.lo);
        let base = |large: bool| {
            let mut v = vec![
                ("hole_diameter", diameter),
                ("hole_height", d.hi - d.lo),
                ("tool_diameter", d_tool),
                ("large_above", large_above),
                ("large", if large { 1.0 } else { 0.0 }),
            ];
            if highest.is_finite() {
                v.push(("separation_height", sep - g.foot));
                v.push(("separation_depth", g.top - sep));
            }
            v
        };
        let (lo, hi) = (d.lo.max(g.foot), d.hi.min(g.top));
        if !is_large(d) {
            eff.inserts.push(Insert {
                owner: d.sf.id,
                shape: d.shape.clone(),
                lo,
                hi,
                placement: Placement::Exposed,
                rule: rule.clone(),
                values: base(false),
                open_at: None,
                note: format!(
                    "{}: small hole ({:.2} mm ≤ {:.2} mm tall) in {}, machined as soon as exposed",
                    d.sf.id,
                    d.hi - d.lo,
                    large_above,
                    sf.id
                ),
            });
            continue;
        }
        // Upper half: after the wall around it (vibration marks otherwise).
        let split = if line { sep.clamp(lo, hi) } else { lo };
        if hi - split > EPS {
            eff.inserts.push(Insert {
                owner: d.sf.id,
                shape: d.shape.clone(),
                lo: split,
                hi,
                placement: Placement::Last,
                rule: rule.clone(),
                values: base(true),
                open_at: None,
                note: format!(
                    "{}: upper half of a large hole in {} (above the step separation line, \
                     {:.2} mm below the wall top), machined after the wall steps beside it",
                    d.sf.id,
                    sf.id,
                    g.top - sep
                ),
            });
        }
        // Lower half: as soon as exposed, split at the wall's large steps
        // below the line (no piece taller than H).
        let mut top = split;
        let mut k = 1.0;
        while top - lo > EPS {
            let next = (split - k * sizes.big_h).max(lo);
            eff.inserts.push(Insert {
                owner: d.sf.id,
                shape: d.shape.clone(),
                lo: next,
                hi: top,
                placement: Placement::Exposed,
                rule: rule.clone(),
                values: base(true),
                open_at: None,
                note: format!(
                    "{}: lower half of a large hole in {}, machined as soon as exposed",
                    d.sf.id, sf.id
                ),
            });
            top = next;
            k += 1.0;
        }
    }
}

/// Figure 4.7: the cut-outs in the wall's top.
pub(crate) fn cutouts(
    ctx: &Ctx,
    sf: &StiffnessFeature,
    g: &WallGeom,
    b: &Cutouts,
    sizes: Sz,
    mode: StrategyMillingMode,
    eff: &mut Effects,
) {
    let rule = format!("{RULE_PREFIX}{}", b.id);
    let mut cuts = depressions(ctx, sf, g, StiffnessKind::Cutout);
    cuts.sort_by(|a, b| a.x0.total_cmp(&b.x0).then(a.sf.id.cmp(&b.sf.id)));
    let (w0, w1) = g.x_range();
    // The ligament: the shortest wall left beside a cut-out (to the next
    // cut-out or the wall's end).
    let ligament = |i: usize| {
        let left = if i == 0 {
            cuts[i].x0 - w0
        } else {
            cuts[i].x0 - cuts[i - 1].x1
        };
        let right = if i + 1 == cuts.len() {
            w1 - cuts[i].x1
        } else {
            cuts[i + 1].x0 - cuts[i].x1
        };
        left.min(right).max(0.0)
    };
    let mut large: Vec<(usize, f64, f64)> = Vec::new();
    for (i, c) in cuts.iter().enumerate() {
        let depth = g.top - c.lo;
        let lig = ligament(i);
        let ratio = if depth > EPS {
            lig / depth
        } else {
            f64::INFINITY
        };
        let is_large =
            depth > b.large_deeper_than_h * sizes.h + EPS || ratio < b.large_below_ligament_ratio;
        if is_large {
            large.push((i, depth, lig));
            continue;
        }
        eff.inserts.push(Insert {
            owner: c.sf.id,
            shape: c.shape.clone(),
            lo: c.lo.max(g.foot),
            hi: c.hi.min(g.top),
            placement: Placement::Exposed,
            rule: rule.clone(),
            values: vec![
                ("cutout_depth", depth),
                ("ligament_length", lig),
                ("ligament_ratio", ratio),
                ("h", sizes.h),
                ("large", 0.0),
            ],
            open_at: None,
            note: format!(
                "{}: small cut-out ({depth:.2} mm deep, h = {}) in {}, inserted in the wall's \
                 sequence as soon as exposed (figure 4.7(b))",
                c.sf.id, sizes.h, sf.id
            ),
        });
    }
    if large.is_empty() {
        return;
    }
    // The wall beside the large cut-outs is a short wall: as long as the
    // shortest ligament, as tall as the deepest cut-out.
    let depth = large.iter().map(|l| l.1).fold(0.0, f64::max);
    let lig = large.iter().map(|l| l.2).fold(f64::INFINITY, f64::min);
    let bottom = (g.top - depth).max(g.foot);
    let short = Wall {
        length: lig.max(EPS),
        thickness: g.t,
        height: depth,
    };
    let m = match mode {
        StrategyMillingMode::Peripheral => MillingMode::Peripheral,
        StrategyMillingMode::Face => MillingMode::Face,
    };
    let zone = match thinplan_sizing::size_wall(&short, &ctx.k.sizing, ctx.e_modulus, m) {
        Ok(s) => Sz {
            b_rf: s.b_rf.max(sizes.b_rf),
            h: s.h.min(sizes.h),
            big_h: s.big_h.min(sizes.big_h),
        },
        Err(e) => {
            eff.warnings.push(format!(
                "{}: the wall beside its cut-outs ({lig:.2} × {depth:.2} mm) cannot be sized \
                 ({e}); stepped in h = {} there",
                sf.id, sizes.h
            ));
            Sz {
                b_rf: sizes.b_rf,
                h: sizes.h,
                big_h: sizes.h,
            }
        }
    };
    eff.breaks.push(Break {
        at: bottom,
        values: vec![("cutout_depth", depth), ("ligament_length", lig)],
    });
    eff.zones.push(Zone {
        lo: bottom,
        hi: g.top,
        sizes: zone,
        why: format!(
            "{rule}: beside large cut-outs, a short wall {lig:.2} mm long (ratio {:.2}) sized \
             h = {}, H = {}, B_RF = {}",
            lig / depth.max(EPS),
            zone.h,
            zone.big_h,
            zone.b_rf
        ),
    });
    // The cut-outs take over the larger permissible height.
    for (i, cdepth, clig) in large {
        let c = &cuts[i];
        let (lo, hi) = (c.lo.max(g.foot), c.hi.min(g.top));
        let mut bands = Vec::new();
        let mut top = hi;
        while top - lo > EPS {
            let next = (top - zone.big_h).max(lo);
            bands.push((next, top));
            top = next;
        }
        // The bottom piece not thinner than min_last_piece.
        if bands.len() > 1 {
            let (l, h) = bands[bands.len() - 1];
            if h - l < b.min_last_piece {
                bands.pop();
                if let Some(last) = bands.last_mut() {
                    last.0 = l;
                }
            }
        }
        let n = bands.len();
        for (j, (l, h)) in bands.into_iter().enumerate() {
            eff.inserts.push(Insert {
                owner: c.sf.id,
                shape: c.shape.clone(),
                lo: l,
                hi: h,
                placement: Placement::Last,
                rule: rule.clone(),
                values: vec![
                    ("cutout_depth", cdepth),
                    ("ligament_length", clig),
                    ("ligament_ratio", clig / cdepth.max(EPS)),
                    ("h", zone.h),
                    ("big_h", zone.big_h),
                    ("large", 1.0),
                ],
                open_at: None,
                note: format!(
                    "{}: large cut-out in {}, piece {} of {n} (steps of H = {}), after the wall \
                     steps beside it (figure 4.7(c))",
                    c.sf.id,
                    sf.id,
                    j + 1,
                    zone.big_h
                ),
            });
        }
    }
}

/// Figure 4.10: the details (chamfers, fillets) across the wall's corners.
/// Each wedge is one feature owned by the detail: right after the wall step
/// that exposes it (reaches down to its bottom), or before all of the
/// wall's features when it is taller than `large_above_big_h` · H.
pub(crate) fn details(
    ctx: &Ctx,
    sf: &StiffnessFeature,
    g: &WallGeom,
    b: &Details,
    sizes: Sz,
    eff: &mut Effects,
) {
    let rule = format!("{RULE_PREFIX}{}", b.id);
    let large_above = b.large_above_big_h * sizes.big_h;
    let mut found = depressions(ctx, sf, g, StiffnessKind::Chamfer);
    found.extend(depressions(ctx, sf, g, StiffnessKind::Fillet));
    found.sort_by_key(|d| d.sf.id);
    for d in &found {
        let (lo, hi) = (d.lo.max(g.foot), d.hi.min(g.top));
        let height = d.hi - d.lo;
        let large = height > large_above + EPS;
        let kind = if d.sf.kind == StiffnessKind::Chamfer {
            "chamfer"
        } else {
            "fillet"
        };
        // The corner the detail replaces, as recognition found it.
        let v = &d.sf.provenance.values;
        let open_at = match (v.get("corner_x"), v.get("corner_y")) {
            (Some(x), Some(y)) => Some(DVec2::new(*x, *y)),
            _ => None,
        };
        eff.inserts.push(Insert {
            owner: d.sf.id,
            shape: d.shape.clone(),
            lo,
            hi,
            placement: if large {
                Placement::First
            } else {
                Placement::Exposed
            },
            rule: rule.clone(),
            values: vec![
                ("detail_height", height),
                ("detail_length", d.x1 - d.x0),
                ("big_h", sizes.big_h),
                ("large_above", large_above),
                ("large", if large { 1.0 } else { 0.0 }),
            ],
            open_at,
            note: if large {
                format!(
                    "{}: large {kind} ({height:.2} mm > {large_above:.2} mm tall) on {}, \
                     machined before all of the wall's features (figure 4.10)",
                    d.sf.id, sf.id
                )
            } else {
                format!(
                    "{}: {kind} ({height:.2} mm ≤ {large_above:.2} mm tall) on {}, machined \
                     with the wall's steps as soon as exposed (figure 4.10)",
                    d.sf.id, sf.id
                )
            },
        });
    }
}

/// Figure 4.6: a flange standing on a web.
pub(crate) fn connected_walls(
    ctx: &Ctx,
    sf: &StiffnessFeature,
    b: &ConnectedWalls,
    sizes: Sz,
    eff: &mut Effects,
) {
    if sf.role != Some(WallRole::Flange) {
        return;
    }
    let rule = format!("{RULE_PREFIX}{}", b.id);
    let mut webs: Vec<&StiffnessFeature> = ctx
        .plan
        .connections
        .iter()
        .filter(|c| c.leaf == sf.id)
        .filter_map(|c| ctx.plan.stiffness_features.iter().find(|f| f.id == c.base))
        .filter(|f| f.kind == StiffnessKind::Wall && f.role == Some(WallRole::Web))
        .collect();
    webs.sort_by_key(|w| w.id);
    webs.dedup_by_key(|w| w.id);
    for web in webs {
        let Some(t) = web.thickness else { continue };
        // The web as a wall held at the flange: face milling across it.
        let wall = Wall {
            length: web.length,
            thickness: t,
            height: web.height,
        };
        let ws = match thinplan_sizing::size_wall(
            &wall,
            &ctx.k.sizing,
            ctx.e_modulus,
            MillingMode::Face,
        ) {
            Ok(s) => s,
            Err(e) => {
                eff.warnings.push(format!(
                    "{}: the web {} it stands on cannot be sized ({e}); its features are not \
                     capped",
                    sf.id, web.id
                ));
                continue;
            }
        };
        let cap = b.width_in_web_big_h * ws.big_h;
        // Narrower than the flange's own B_RF: the flange would lose the
        // support the sizing model counts on, so only its foot is capped.
        let local = cap < sizes.b_rf - EPS;
        eff.width_caps.push(WidthCap {
            cap,
            local,
            rule: rule.clone(),
            values: vec![
                ("web", f64::from(web.id.0)),
                ("web_big_h", ws.big_h),
                ("width_cap", cap),
                ("local", if local { 1.0 } else { 0.0 }),
            ],
            note: format!(
                "width ≤ {cap:.2} mm, the permissible height H = {} of web {} (figure 4.6){}",
                ws.big_h,
                web.id,
                if local {
                    ", at the flange's foot only (less than B_RF)"
                } else {
                    ""
                }
            ),
        });
    }
}
