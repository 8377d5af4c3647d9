//! The rest region's pattern at every z-level: what the tool clears
//! inside the boundary passes before they run. A closed pocket takes the
//! pocketing crate's spiral (entered by a helix about its centre where one
//! fits); otherwise parallel blocks whose line count and first pass's end
//! make one level flow into the boundary pass and the next level start
//! where this one ended, mirrored on alternate levels where the method
//! asks and no boundary pass fixes the direction.

use glam::DVec2;
use thinplan_knowledge::{FullCut, LevelEntry, Method, MirrorLayers, Pattern, SidesMatch};
use thinplan_plan::MachiningFeature;

use super::band::BandPlan;
use super::boundary::end_of;
use super::parallel::parallel_blocks;
use super::plan_view::product_distance;
use super::region::Geometry;
use crate::geom::{adjacency_edges, boundary_distance, inside, oriented, pline_from_edges};

/// The rest pattern of every z-level of a band, with what it adds to the
/// levels' operation's provenance.
pub(super) struct LevelPattern {
    pub(super) plan: RestPlan,
    /// Provenance values of the choice.
    pub(super) values: Vec<(&'static str, f64)>,
    pub(super) notes: Vec<String>,
    /// Alternate levels run the blocks backwards.
    pub(super) mirror: bool,
}

/// The rest pattern of one z-level, chosen once for all levels: the
/// spiral, or the parallel blocks matched to the boundary passes, with
/// whether alternate levels are mirrored and (where the method asks) how
/// alternating full cuts would compare.
pub(super) fn rest_pattern(
    band: &BandPlan,
    sides: SidesMatch,
    warnings: &mut Vec<String>,
) -> Result<LevelPattern, String> {
    let (f, m, g, d) = (band.f, band.m, band.g, band.d);
    let mk = &band.env.k.methods;
    let (spacing, s_b) = (band.spacing, band.boundary.s_b);
    let passes = &band.boundary.passes;
    let mut rest_plan = RestPlan::default();
    let mut prov_values: Vec<(&'static str, f64)> = Vec::new();
    let mut notes = vec![
        format!("pattern={:?}", m.pattern),
        format!("sides={sides:?}"),
    ];
    let mut mirror = false;
    if m.pattern.is_spiral() {
        rest_plan = spiral_rest(f, m, g, d, spacing, s_b, true, &mk.fit_scales, &mut notes)?;
    } else if !band.boundary.rest_polys.is_empty() {
        let oneway = (m.pattern == Pattern::OneWay).then_some(band.oneway_dir);
        if let Some(p) = parity_matched(band, oneway) {
            rest_plan = p;
        }
        let side_passes = rest_plan.lines + usize::from(!passes.is_empty());
        prov_values.push(("side_passes", side_passes as f64));
        // Mirrored alternating z-levels where a level ends away from its start.
        let first = rest_plan.blocks.first().map(|b| b[0]);
        let last = rest_plan.blocks.last().and_then(|b| b.last().copied());
        let ends_away = match (first, last) {
            (Some(a), Some(b)) => a.distance(b) > d,
            _ => false,
        };
        mirror = match m.mirror_layers {
            MirrorLayers::Never => false,
            MirrorLayers::Always => true,
            MirrorLayers::WhenOddPasses => ends_away,
        } && passes.is_empty()
            && oneway.is_none();
        if !passes.is_empty() && m.mirror_layers != MirrorLayers::Never && ends_away {
            notes.push(
                "mirror=refused-product-sides(down milling fixes the boundary direction)".into(),
            );
        }
        full_cut_criterion(band, &rest_plan, side_passes, &mut prov_values, warnings);
    }
    if mirror {
        notes.push("mirror=alternate".into());
    }
    Ok(LevelPattern {
        plan: rest_plan,
        values: prov_values,
        notes,
        mirror,
    })
}

/// Parity (§4.3.3, figure 4.22): the line count and the first pass's end
/// chosen so one z-level flows into the boundary pass and the next z-level
/// starts where this one ended. `None` where no line crosses the rest
/// region.
fn parity_matched(band: &BandPlan, oneway: Option<DVec2>) -> Option<RestPlan> {
    let g = band.g;
    let spacing = band.spacing;
    let passes = &band.boundary.passes;
    let mut best: Option<(f64, usize, RestPlan)> = None;
    for extra in [false, true] {
        for high in [false, true] {
            let (blocks, n) = parallel_blocks(
                &band.boundary.rest_polys,
                (&g.region_polys, g.r),
                band.dir,
                band.progress,
                spacing,
                extra,
                high,
                oneway,
            );
            if blocks.is_empty() {
                continue;
            }
            let first = blocks[0][0];
            let last = *blocks.last().and_then(|b| b.last()).unwrap_or(&first);
            let cost = match (passes.first(), passes.last()) {
                (Some(p), Some(q)) => last.distance(p.start) + end_of(q).distance(first),
                _ => 0.0,
            } + if extra { spacing * 0.5 } else { 0.0 };
            let better = best.as_ref().is_none_or(|b| cost < b.0 - 1e-9);
            if better {
                best = Some((
                    cost,
                    n,
                    RestPlan {
                        blocks,
                        lines: n,
                        helix: None,
                    },
                ));
            }
            if passes.is_empty() {
                break;
            }
        }
        if passes.is_empty() {
            break;
        }
    }
    best.map(|(_, _, p)| p)
}

/// §6.3.3 full-cut criterion: alternating layers with a full cut in every
/// second one vs. the parity-matched pattern used here, compared in side
/// passes (provenance) and said where the alternative would take fewer.
fn full_cut_criterion(
    band: &BandPlan,
    rest_plan: &RestPlan,
    side_passes: usize,
    prov_values: &mut Vec<(&'static str, f64)>,
    warnings: &mut Vec<String>,
) {
    let FullCut::WhenFewerSidePasses { depth_factor } = band.m.full_cut else {
        return;
    };
    if band.boundary.passes.is_empty() {
        return;
    }
    let h = &band.h;
    let l = h.zs.len();
    let pair = h.a_rest * (1.0 + depth_factor);
    let l_fc = 2 * ((h.z_top - h.z_main_bottom) / pair - 1e-9).ceil().max(1.0) as usize;
    let base = rest_plan.lines.saturating_sub(1).max(1) + 1;
    let alt = l_fc * base + l_fc / 2;
    let used = l * side_passes;
    prov_values.push(("full_cut_alternating_passes", alt as f64));
    prov_values.push(("parity_matched_passes", used as f64));
    if alt < used {
        warnings.push(format!(
            "{}: alternating layers with a full cut would take fewer side passes \
             ({alt} < {used}); not built, the parity-matched pattern is used",
            band.f.id
        ));
    }
}

/// The rest pattern of one z-level: its blocks and how many lines they
/// run along.
#[derive(Default)]
pub(super) struct RestPlan {
    pub(super) blocks: Vec<Vec<DVec2>>,
    pub(super) lines: usize,
    /// A helix about the spiral's centre (centre, tool-centre radius) the
    /// first block starts on: the spiral inside its circle is left out.
    pub(super) helix: Option<(DVec2, f64)>,
}

/// The rest region of a closed pocket: the pocketing crate's curvilinear
/// spiral (or offset rings), without its finishing ring (the boundary pass
/// replaces it with true arcs).
#[allow(clippy::too_many_arguments)]
pub(super) fn spiral_rest(
    f: &MachiningFeature,
    m: &Method,
    g: &Geometry,
    d: f64,
    stepover: f64,
    s_b: f64,
    centred_helix: bool,
    fit_scales: &[f64],
    notes: &mut Vec<String>,
) -> Result<RestPlan, String> {
    use thinplan_pocketing::{curvilinear_path, offset_path, Pocket, PocketParams};
    let edges = adjacency_edges(&f.shape.region, &f.side_adjacency, &f.hole_adjacency);
    let outer = oriented(pline_from_edges(&edges[0].0, true), true);
    let islands = edges[1..]
        .iter()
        .map(|(es, _)| oriented(pline_from_edges(es, true), false))
        .collect();
    let pocket = Pocket::with_islands(format!("{}", f.id), outer, islands);
    let mut params = PocketParams::for_tool(d);
    params.stepover = stepover.min(d);
    params.finish_stepover = s_b.min(params.stepover);
    let res = if m.pattern == Pattern::CurvilinearSpiral {
        curvilinear_path(&pocket, &params).or_else(|_| offset_path(&pocket, &params))
    } else {
        offset_path(&pocket, &params)
    }
    .map_err(|e| format!("pocket path: {e}"))?;
    notes.push(format!("spiral={}", res.method.as_str()));
    if let Some(r) = &res.fallback_reason {
        notes.push(format!("fallback={r}"));
    }
    // A spiral about a centre entered by a helix about that centre (the
    // method's radius, shrunk as stage 7's fit rule does): the helix clears
    // a hole of radius ρ + r, so the spiral starts where it leaves the
    // circle (no slotting first turn around a plunge hole).
    let mut helix = None;
    let mut res = res;
    if let (true, LevelEntry::Helix { radius, .. }, Some(_)) = (centred_helix, m.entry, res.center)
    {
        let radii: Vec<f64> = fit_scales.iter().map(|s| radius * d * s).collect();
        if let Some((trimmed, h)) = res.after_centred_helix(&radii) {
            let fits = inside(h.center, &g.centre_polys)
                && boundary_distance(h.center, &g.centre_polys) >= h.radius + 1e-6
                && product_distance(h.center, &g.product) >= g.r + h.radius;
            if fits {
                notes.push(format!("entry=centred helix r={:.3}", h.radius));
                helix = Some((h.center, h.radius));
                res = trimmed;
            }
        }
    }
    let mut pts: Vec<DVec2> = res.points[..res.finish_start.min(res.points.len())].to_vec();
    // Keep only points the tool centre may reach (the pocket crate offsets
    // the same region; this guards against its sampling chords).
    pts.retain(|p| product_distance(*p, &g.product) >= g.r + 0.5 * s_b);
    if pts.len() < 2 {
        return Ok(RestPlan::default());
    }
    Ok(RestPlan {
        blocks: vec![pts],
        lines: 1,
        helix,
    })
}
