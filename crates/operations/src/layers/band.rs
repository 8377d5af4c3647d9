//! One band of a feature, planned as the modular pattern: the method its
//! adjacency selects and the tool, the boundary passes along the product
//! and the rest region inside them, every z-level's operation and the
//! bottom layer's, and the rest passes after them. `plan_band_with` is
//! the orchestrator; each step lives with its concept.

use glam::DVec2;
use thinplan_knowledge::{BottomLayer, Method, SlopedFaces, Tool};
use thinplan_plan::{Adjacency, MachiningFeature, Provenance, Schedule};

use super::boundary::{boundary_region, Boundary};
use super::levels::{bottom_layer_op, heights, level_op, Heights};
use super::parallel::{pass_direction, spin_sign};
use super::region::{geometry, unreached_area, Geometry};
use super::rest_passes::{cuts_of, orphan_passes, rest_passes, RestCtx};
use super::rest_region::rest_pattern;
use super::slopes::{slope_shifts, Slopes};
use super::tool_choice::{choose_tool, clamped_to_reach, conditions, method_for, Chosen};
use super::{Env, LocalOp, Made, STEP};
use crate::geom::Edge2;
use crate::path::{Builder, Space};

/// One band of a feature (the whole of it, or the levels between two
/// heights), its sloped product faces taken as far as the knowledge and
/// the stage 6 samples allow.
pub(super) fn plan_band(
    f: &MachiningFeature,
    env: &Env,
    free: Option<&crate::free::Shapes>,
    removed: Option<&crate::free::Shapes>,
) -> Result<Made, String> {
    if f.slopes.is_none() || env.k.methods.sloped_faces == SlopedFaces::AsVertical {
        return plan_band_with(f, env, free, removed, Slopes::AsVertical);
    }
    if let Some(why) = f.slopes.as_ref().and_then(|s| s.unusable()) {
        let mut m = plan_band_with(f, env, free, removed, Slopes::AsVertical)?;
        m.warnings.push(format!(
            "{}: its sampled sloped faces cannot be used ({why}); planned as vertical, \
             material stays on them",
            f.id
        ));
        return Ok(m);
    }
    // Sloped product faces: followed where the safety net holds (swept at
    // the edges' ends, else one shift per edge), else planned as vertical
    // at the region's section (material stays, none is cut beyond it),
    // and said.
    let followed = plan_band_with(f, env, free, removed, Slopes::Swept)
        .or_else(|_| plan_band_with(f, env, free, removed, Slopes::Shifted));
    match followed {
        Ok(mut m) => {
            // Provenance: how far the product edges moved for each tool.
            for op in &mut m.ops {
                let Some(tool) = env.tools.tools.iter().find(|t| t.id == op.tool) else {
                    continue;
                };
                if let Some(sh) = slope_shifts(f, tool) {
                    let most =
                        sh.into_iter()
                            .flatten()
                            .fold(0.0, |a: f64, b| if b.abs() > a.abs() { b } else { a });
                    op.provenance.values.insert("slope_shift_mm".into(), most);
                    op.provenance.note.push_str("; sloped_faces=Follow");
                }
            }
            Ok(m)
        }
        Err(e) => {
            let mut m = plan_band_with(f, env, free, removed, Slopes::AsVertical)?;
            m.warnings.push(format!(
                "{}: its sloped product faces cannot be followed ({e}); planned as vertical, \
                 material stays on them",
                f.id
            ));
            Ok(m)
        }
    }
}

/// One band planned with its sloped faces taken one way: the method and
/// tool, the boundary passes and rest pattern, the levels' and the bottom
/// layer's operations, then the rest passes.
fn plan_band_with(
    f: &MachiningFeature,
    env: &Env,
    free: Option<&crate::free::Shapes>,
    removed: Option<&crate::free::Shapes>,
    slopes: Slopes,
) -> Result<Made, String> {
    let (edges, sides, m) = method_for(f, &env.k.methods)?;
    let mut warnings = Vec::new();
    let fits = |t: &Tool| geometry(f, m, t, free, removed, slopes);
    let chosen = choose_tool(f, env, m, &edges, fits, &mut warnings)?;
    // A tool that fits but does not reach the floor cuts the levels it
    // reaches; below them the feature is refused, naming the tool it needs.
    let (clamped, reach_left) = match clamped_to_reach(env, f, chosen.tool, &mut warnings)? {
        Some(c) => (Some(c.feature), Some(c.left)),
        None => (None, None),
    };
    let f = clamped.as_ref().unwrap_or(f);
    // The corners' volume: the region less what the tool's disc sweeps,
    // over the feature's depth.
    let depth = f.shape.z_max - f.shape.z_min;
    let unreachable: Vec<(String, f64)> = chosen
        .corners_left
        .iter()
        .map(|r| (r.clone(), unreached_area(&chosen.g) * depth))
        .chain(reach_left)
        .collect();
    let band = BandPlan::new(f, env, m, &chosen, &edges, &mut warnings)?;
    let pattern = rest_pattern(&band, sides, &mut warnings)?;
    let mut ops = Vec::new();
    ops.extend(level_op(&band, &pattern)?);
    if let Some(bl) = band.bottom_layer {
        ops.extend(bottom_layer_op(&band, bl)?);
    }
    let wall_levels = band.h.wall_levels();
    let own_cuts = cuts_of(env, &ops);
    let ctx = RestCtx {
        f,
        m,
        env,
        free,
        removed,
        own_cuts: &own_cuts,
        tool: chosen.tool,
        g: &chosen.g,
        after: None,
        z_min: band.h.z_min,
        z_top: band.h.z_top,
        levels: &wall_levels,
        safe_z: band.h.safe_z,
        rapid_floor: band.h.rapid_floor,
        geometries: Default::default(),
    };
    // Stage 7's second pass: only the orphan stretches.
    if let Some(cov) = env.orphans {
        let orphan = orphan_passes(&ctx, cov, &mut warnings);
        return Ok(Made {
            ops: orphan,
            warnings,
            unreachable: Vec::new(),
            reach: chosen.g.centre_polys.clone(),
        });
    }
    rest_passes(&ctx, band.bottom_product(), &mut ops, &mut warnings);
    if ops.is_empty() {
        return Err("the tool-centre region is empty at every z-level".into());
    }
    Ok(Made {
        ops,
        warnings,
        unreachable,
        reach: chosen.g.centre_polys.clone(),
    })
}

/// What the steps of one band's plan share once its method and tool are
/// chosen.
pub(super) struct BandPlan<'b> {
    /// The band, cut short where the tool does not reach its floor.
    pub(super) f: &'b MachiningFeature,
    pub(super) env: &'b Env<'b>,
    pub(super) m: &'b Method,
    pub(super) tool: &'b Tool,
    pub(super) g: &'b Geometry,
    /// The smallest product corner's radius (provenance).
    pub(super) corner: Option<f64>,
    /// The tool's diameter.
    pub(super) d: f64,
    /// Spindle speed and feeds (mm/min).
    pub(super) rpm: f64,
    pub(super) feed_rough: f64,
    pub(super) feed_finish: f64,
    pub(super) feed_boundary: f64,
    /// The rest region's stepover (mm).
    pub(super) spacing: f64,
    pub(super) boundary: Boundary,
    /// The parallel lines' direction and the way they progress.
    pub(super) dir: DVec2,
    pub(super) progress: DVec2,
    /// The travel of one-way lines: down milling.
    pub(super) oneway_dir: DVec2,
    /// The entries' angle (rad).
    pub(super) angle: f64,
    /// The method's bottom layer, where the band's floor is product.
    pub(super) bottom_layer: Option<&'b BottomLayer>,
    pub(super) h: Heights,
}

impl<'b> BandPlan<'b> {
    /// The band's conditions, boundary passes and rest region, pass
    /// direction and heights for the chosen tool.
    fn new(
        f: &'b MachiningFeature,
        env: &'b Env<'b>,
        m: &'b Method,
        chosen: &'b Chosen<'b>,
        edges: &[(Vec<Edge2>, Vec<Adjacency>)],
        warnings: &mut Vec<String>,
    ) -> Result<BandPlan<'b>, String> {
        let mk = &env.k.methods;
        let (tool, g) = (chosen.tool, &chosen.g);
        let d = tool.diameter;
        let (rpm, feed_rough, feed_finish) = conditions(env, tool);
        let boundary = m.boundary.as_ref().filter(|_| !g.product.is_empty());
        let feed_boundary = match boundary {
            Some(b) if b.finishing => feed_finish,
            _ => feed_rough,
        };
        let split = boundary_region(f, g, boundary, d, mk, warnings);
        let (dir, progress) = pass_direction(edges, g)?;
        let bottom_product = f.bottom_adjacency == Adjacency::Product;
        let bottom_layer = m.bottom_layer.as_ref().filter(|_| bottom_product);
        let h = heights(env, f, m, tool, boundary, bottom_layer);
        Ok(BandPlan {
            f,
            env,
            m,
            tool,
            g,
            corner: chosen.corner,
            d,
            rpm,
            feed_rough,
            feed_finish,
            feed_boundary,
            spacing: m.rest.stepover * d,
            boundary: split,
            dir,
            progress,
            oneway_dir: -progress.perp() * spin_sign(mk.spindle),
            angle: m.entry.angle_deg().to_radians(),
            bottom_layer,
            h,
        })
    }

    /// Whether the band's floor is product.
    fn bottom_product(&self) -> bool {
        self.f.bottom_adjacency == Adjacency::Product
    }

    /// Where the band's links may run: its tool-centre region, from the
    /// top of the stock (rapids) up to the safe height, where `clear`.
    pub(super) fn space<'s>(&'s self, clear: &'s dyn Fn(glam::DVec3) -> bool) -> Space<'s> {
        Space {
            centre_region: &self.g.centre_polys,
            z_top: self.h.rapid_floor,
            safe_z: self.h.safe_z,
            step: STEP,
            clear: Some(clear),
        }
    }

    /// The rule of the band's operations in the knowledge.
    pub(super) fn rule(&self) -> String {
        format!("methods.{}", self.m.id)
    }

    /// The provenance values every operation of the band carries: tool,
    /// conditions, stepovers, depth of cut and levels.
    pub(super) fn base_values(
        &self,
        prov: &mut Provenance,
        stepover: f64,
        depth: f64,
        layers: usize,
    ) {
        prov.values.insert("tool_diameter_mm".into(), self.d);
        prov.values.insert("spindle_rpm".into(), self.rpm);
        prov.values
            .insert("feed_rough_mm_min".into(), self.feed_rough);
        prov.values
            .insert("feed_finish_mm_min".into(), self.feed_finish);
        prov.values
            .insert("feed_boundary_mm_min".into(), self.feed_boundary);
        prov.values.insert("stepover_rest_mm".into(), stepover);
        prov.values
            .insert("stepover_boundary_mm".into(), self.boundary.s_b);
        prov.values.insert("depth_of_cut_mm".into(), depth);
        prov.values.insert("layers".into(), layers as f64);
        if let Some(c) = self.corner {
            prov.values.insert("smallest_product_corner_mm".into(), c);
        }
    }

    /// An operation of the band with the tool's conditions.
    pub(super) fn local_op(&self, moves: Builder, prov: Provenance) -> LocalOp {
        LocalOp {
            method: self.m.id.clone(),
            tool: self.tool.id.clone(),
            rpm: self.rpm,
            feed_rough: self.feed_rough,
            feed_finish: self.feed_finish,
            feed_boundary: self.feed_boundary,
            feed_link: self.feed_rough * self.env.k.methods.link_feed_factor,
            start: moves.start,
            moves: moves.moves,
            schedule: Schedule::WithFeature,
            provenance: prov,
        }
    }
}
