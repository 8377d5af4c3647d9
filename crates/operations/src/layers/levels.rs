//! The z-levels of a band and the operations that cut them: levels from
//! the top by the method's depth of cut, each cut by the rest pattern's
//! blocks and then the boundary passes; the product-adjacent bottom layer
//! on its own with finishing conditions; the safe and rapid heights in the
//! feature's frame.

use glam::{DVec2, DVec3};
use thinplan_knowledge::{BottomLayer, BoundaryRegion, FullCut, Method, Pattern, Tool};
use thinplan_plan::{MachiningFeature, Provenance, ProvenanceSource};

use super::band::BandPlan;
use super::entries::{boundary_level, enter, go_to, retract};
use super::parallel::parallel_blocks;
use super::rest_region::{spiral_rest, LevelPattern};
use super::safety_net::{check, Net};
use super::slopes::slope_values;
use super::{Env, LocalOp};
use crate::path::{rounded, Builder, Kind};

/// Rest blocks shorter than this (mm) are points where a zigzag line only
/// touches the tool-centre region.
const MIN_BLOCK: f64 = 1e-3;

/// A block the zigzag only touches (a rest region pinched to a point): it
/// has no length to ramp along and cuts no more than the disc a
/// neighbouring pass takes, so a level skips it where no entry fits.
fn pinched(block: &[DVec2]) -> bool {
    block.windows(2).map(|w| w[0].distance(w[1])).sum::<f64>() < MIN_BLOCK
}

/// The heights of a band's levels (local z).
pub(super) struct Heights {
    pub(super) z_top: f64,
    pub(super) z_min: f64,
    /// Where the levels end: the bottom layer's top, else the floor.
    pub(super) z_main_bottom: f64,
    /// The levels' depth of cut in the rest region.
    pub(super) a_rest: f64,
    /// The boundary passes' depth of cut (they stack within a level).
    pub(super) a_b: f64,
    /// The levels, top down.
    pub(super) zs: Vec<f64>,
    /// Links that leave the tool-centre region run here.
    pub(super) safe_z: f64,
    /// Where rapids down end: the top of the stock.
    pub(super) rapid_floor: f64,
}

/// The heights of a band of `f` cut by `tool` under method `m`: levels
/// from its top by the method's depth of cut (the flute length at most)
/// down to the bottom layer, and the safe and rapid heights in the
/// feature's frame.
pub(super) fn heights(
    env: &Env,
    f: &MachiningFeature,
    m: &Method,
    tool: &Tool,
    boundary: Option<&BoundaryRegion>,
    bottom_layer: Option<&BottomLayer>,
) -> Heights {
    let mk = &env.k.methods;
    let d = tool.diameter;
    let flute = tool.flute_length;
    let z_top = f.shape.z_max;
    let z_min = f.shape.z_min;
    let z_main_bottom = match bottom_layer {
        Some(b) => (z_min + b.thickness).min(z_top),
        None => z_min,
    };
    let mut a_rest = (m.rest.depth * d).min(flute);
    if let FullCut::Always { depth_factor } = m.full_cut {
        a_rest *= depth_factor;
    }
    let a_b = boundary.map_or(f64::INFINITY, |b| (b.depth * d).min(flute));
    let zs = levels(z_top, z_main_bottom, a_rest);
    let safe_z = env.global_top.max(z_top) + mk.safe_clearance;
    // Local heights: the global top is along `up`; the feature's frame
    // origin sits on that axis at origin·up.
    let up_off = f
        .shape
        .frame
        .origin
        .dot(f.shape.frame.z.normalize_or_zero());
    let safe_z = (safe_z - up_off).max(z_top + mk.safe_clearance);
    // Rapids stop at the top of the stock, not of the feature: material
    // that features above leave (corners no tool reaches, refused
    // features) may stand over this one; the rest of the way down is fed.
    let rapid_floor = (env.global_top - up_off).clamp(z_top, safe_z);
    Heights {
        z_top,
        z_min,
        z_main_bottom,
        a_rest,
        a_b,
        zs,
        safe_z,
        rapid_floor,
    }
}

impl Heights {
    /// The levels of the feature's passes, top down, the floor last: those
    /// the wall rest passes run at.
    pub(super) fn wall_levels(&self) -> Vec<f64> {
        let mut wall_levels: Vec<f64> = self.zs.clone();
        if wall_levels.last().is_none_or(|z| *z > self.z_min + 1e-9) {
            wall_levels.push(self.z_min);
        }
        wall_levels
    }
}

/// The z-levels of a range from the top: `n` levels `dz` apart.
fn levels(top: f64, bottom: f64, depth: f64) -> Vec<f64> {
    let h = top - bottom;
    if h <= 1e-9 {
        return Vec::new();
    }
    let n = (h / depth - 1e-9).ceil().max(1.0) as usize;
    (1..=n)
        .map(|i| {
            if i == n {
                bottom
            } else {
                top - h * i as f64 / n as f64
            }
        })
        .collect()
}

/// The levels' operation: at each level the rest pattern's blocks, entered
/// by helix or ramp (a pinched block where neither fits is skipped), then
/// the boundary passes; `None` where no level has a move.
pub(super) fn level_op(band: &BandPlan, pattern: &LevelPattern) -> Result<Option<LocalOp>, String> {
    let (f, m, g, d) = (band.f, band.m, band.g, band.d);
    let mk = &band.env.k.methods;
    let h = &band.h;
    let (passes, rest_polys) = (&band.boundary.passes, &band.boundary.rest_polys);
    let rest_plan = &pattern.plan;
    let net = Net::new(g);
    let clear = |p: DVec3| net.touches(p, Kind::Link).is_none();
    let space = band.space(&clear);
    let full_cut_always = matches!(m.full_cut, FullCut::Always { .. });
    let entry_kind = if full_cut_always {
        Kind::FullCut
    } else {
        Kind::Rest
    };
    let rho_c = m.corner_rounding * d;
    let mut main = Builder::new(DVec3::ZERO);
    let mut started = false;
    let mut z_prev = h.z_top;
    let mut layer_count = 0;
    for (li, &z) in h.zs.iter().enumerate() {
        let reversed = pattern.mirror && li % 2 == 1;
        let blocks: Vec<Vec<DVec2>> = if reversed {
            rest_plan
                .blocks
                .iter()
                .rev()
                .map(|b| b.iter().rev().copied().collect())
                .collect()
        } else {
            rest_plan.blocks.clone()
        };
        for (bi, block) in blocks.iter().enumerate() {
            if block.len() < 2 {
                continue;
            }
            go_to(&mut main, &mut started, &space, block[0], z_prev);
            let kind = if full_cut_always && bi == 0 {
                Kind::FullCut
            } else {
                Kind::Rest
            };
            let mark = (main.moves.len(), main.pos);
            if enter(
                &mut main,
                m.entry,
                block,
                z_prev,
                z,
                band.angle,
                d,
                g,
                if bi == 0 { rest_plan.helix } else { None },
                mk,
                entry_kind,
            )
            .is_none()
            {
                if pinched(block) {
                    main.moves.truncate(mark.0);
                    main.pos = mark.1;
                    continue;
                }
                return Err(format!("no room to ramp into z-level {z:.3}"));
            }
            let segs = rounded(block, rho_c);
            if full_cut_always && bi == 0 && m.pattern.is_spiral() {
                // The first orbit of a spiral cuts the full width.
                let p0 = block[0];
                for s in &segs {
                    let k = if s.to.distance(p0) <= band.spacing {
                        Kind::FullCut
                    } else {
                        Kind::Rest
                    };
                    main.follow(std::slice::from_ref(s), z, k);
                }
            } else {
                main.follow(&segs, z, kind);
            }
        }
        boundary_level(
            &mut main,
            &mut started,
            &space,
            passes,
            rest_polys,
            z_prev,
            z,
            h.a_b,
            band.angle,
        );
        z_prev = z;
        layer_count += 1;
    }
    if main.moves.is_empty() {
        return Ok(None);
    }
    retract(&mut main, h.safe_z);
    let mut prov = Provenance::new(ProvenanceSource::Knowledge, band.rule());
    band.base_values(
        &mut prov,
        band.spacing,
        (h.z_top - h.z_main_bottom) / layer_count.max(1) as f64,
        layer_count,
    );
    slope_values(&mut prov, g);
    for (k, v) in &pattern.values {
        prov.values.insert((*k).into(), *v);
    }
    prov.note = pattern.notes.join("; ");
    check(&main, g, h.z_min, h.z_top, f)?;
    Ok(Some(band.local_op(main, prov)))
}

/// The product-adjacent bottom layer: its own operation, finishing
/// conditions on all of it (§4.3.4, §6.3.1); `None` where it has no move.
pub(super) fn bottom_layer_op(
    band: &BandPlan,
    bl: &BottomLayer,
) -> Result<Option<LocalOp>, String> {
    let (f, m, g, d) = (band.f, band.m, band.g, band.d);
    let mk = &band.env.k.methods;
    let h = &band.h;
    let (passes, rest_polys) = (&band.boundary.passes, &band.boundary.rest_polys);
    let net = Net::new(g);
    let clear = |p: DVec3| net.touches(p, Kind::Link).is_none();
    let space = band.space(&clear);
    let rho_c = m.corner_rounding * d;
    let so = bl.stepover * d;
    let mut b = Builder::new(DVec3::ZERO);
    let mut started = false;
    let top = h.z_main_bottom;
    let mut bnotes = vec![
        format!("pattern={:?}", bl.pattern),
        "layer=bottom".to_string(),
    ];
    let blocks: Vec<Vec<DVec2>> = if bl.pattern.is_spiral() {
        let mut mm = m.clone();
        mm.pattern = bl.pattern;
        let s_b = band.boundary.s_b;
        spiral_rest(f, &mm, g, d, so, s_b, false, &mk.fit_scales, &mut bnotes)?.blocks
    } else {
        let oneway = (bl.pattern == Pattern::OneWay).then_some(band.oneway_dir);
        parallel_blocks(
            rest_polys,
            (&g.region_polys, g.r),
            band.dir,
            band.progress,
            so,
            false,
            false,
            oneway,
        )
        .0
    };
    for block in &blocks {
        if block.len() < 2 {
            continue;
        }
        go_to(&mut b, &mut started, &space, block[0], top);
        let mark = (b.moves.len(), b.pos);
        if enter(
            &mut b,
            m.entry,
            block,
            top,
            h.z_min,
            band.angle,
            d,
            g,
            None,
            mk,
            Kind::BottomFinish,
        )
        .is_none()
        {
            if pinched(block) {
                b.moves.truncate(mark.0);
                b.pos = mark.1;
                continue;
            }
            return Err("no room to ramp into the bottom layer".into());
        }
        b.follow(&rounded(block, rho_c), h.z_min, Kind::BottomFinish);
    }
    boundary_level(
        &mut b,
        &mut started,
        &space,
        passes,
        rest_polys,
        top,
        h.z_min,
        h.a_b,
        band.angle,
    );
    if b.moves.is_empty() {
        return Ok(None);
    }
    retract(&mut b, h.safe_z);
    let mut prov = Provenance::new(
        ProvenanceSource::Knowledge,
        format!("{}.bottom_layer", band.rule()),
    );
    band.base_values(&mut prov, so, top - h.z_min, 1);
    slope_values(&mut prov, g);
    prov.note = bnotes.join("; ");
    check(&b, g, h.z_min, h.z_top, f)?;
    Ok(Some(band.local_op(b, prov)))
}
