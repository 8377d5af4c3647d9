//! The `WebFaceMill` block: a web face-milled top-down in layers.
//!
//! The layers cover the web's outline, from the top of the blank down to the
//! web's up face, `layer_depth` deep each (the last one shallower). Walls
//! that stand over the web's outline (a rib on it, a flange at its edge)
//! have their own step features there, and without 2D booleans the layers
//! cannot yet leave them out; so when such walls exist the layers start
//! above the highest of them, and the material between the web and that
//! height, beside the walls' features, is left to the remaining-material
//! stage (a warning says so). The web's down side is for another set-up.

use glam::DVec3;
use thinplan_knowledge::WebFaceMill;
use thinplan_plan::{
    Adjacency, FeatureOrigin, MachiningFeature, MachiningFeatureId, Prism, PrismFrame, ProfileLoop,
    ProfileVertex, Provenance, ProvenanceSource, Region, StiffnessFeature,
};

use crate::{area2, prism_points, span, Ctx, Determination, WallGeom, EPS, RULE_PREFIX};

pub(crate) fn face_mill(
    ctx: &Ctx,
    sf: &StiffnessFeature,
    g: &WallGeom,
    b: &WebFaceMill,
    out: &mut Determination,
) -> Vec<MachiningFeatureId> {
    let rule = format!("{RULE_PREFIX}{}", b.id);
    let c = g.n.dot(ctx.up);
    let tilt = c.abs().clamp(0.0, 1.0).acos().to_degrees();
    if tilt > b.max_tilt_deg {
        out.warnings.push(format!(
            "{}: a web tilted {tilt:.1}° from the spindle axis, more than block `{}` \
             face-mills ({:.1}°); not face-milled",
            sf.id, b.id, b.max_tilt_deg
        ));
        return Vec::new();
    }
    let s = c.signum();
    let face = g.origin + g.n * (s * 0.5 * g.t);
    let web_top = face.dot(ctx.up);
    let (_, blank_top) = span(ctx.blank, ctx.up);
    // The web's footprint across the spindle axis.
    let e1 = ctx.up.any_orthonormal_vector();
    let e2 = ctx.up.cross(e1);
    let web_pts = prism_points(sf.shape.as_ref().expect("a wall geometry has a shape"));
    let overlaps = |pts: &[DVec3]| {
        [e1, e2].iter().all(|d| {
            let (a0, a1) = span(&web_pts, *d);
            let (b0, b1) = span(pts, *d);
            a1.min(b1) - a0.max(b0) > EPS
        })
    };
    let mut from = web_top;
    let mut over = Vec::new();
    for other in &ctx.plan.stiffness_features {
        if other.id == sf.id || other.role.is_none() {
            continue;
        }
        let Some(shape) = other.shape.as_ref() else {
            continue;
        };
        let pts = prism_points(shape);
        let (_, hi) = span(&pts, ctx.up);
        if hi > web_top + EPS && overlaps(&pts) {
            from = from.max(hi);
            over.push(other.id.to_string());
        }
    }
    if !over.is_empty() {
        out.warnings.push(format!(
            "{}: walls {} stand over the web; its face-milling layers start at {from:.3} \
             (the web's face is at {web_top:.3}); the material between, beside their \
             features, is left to the remaining-material stage",
            sf.id,
            over.join(", ")
        ));
    }
    let depth = blank_top - from;
    if depth <= EPS {
        return Vec::new();
    }
    let n = ((depth / b.layer_depth) - 1e-9).ceil().max(1.0) as usize;
    let mut pts: Vec<_> = g
        .outline
        .iter()
        .map(|q| glam::DVec2::new(q.x, s * q.y))
        .collect();
    if area2(&pts) < 0.0 {
        pts.reverse();
    }
    let region = Region {
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
    };
    let mut chain: Vec<MachiningFeatureId> = Vec::new();
    for i in 0..n {
        let hi = blank_top - b.layer_depth * i as f64;
        let lo = (blank_top - b.layer_depth * (i + 1) as f64).max(from);
        let id = MachiningFeatureId(out.features.len() as u32);
        let mut prov = Provenance::new(ProvenanceSource::Knowledge, rule.clone())
            .with_value("layer_depth", b.layer_depth)
            .with_value("layer", (i + 1) as f64)
            .with_value("from", lo)
            .with_value("to", hi)
            .with_value("access_x", ctx.up.x)
            .with_value("access_y", ctx.up.y)
            .with_value("access_z", ctx.up.z);
        prov.note = format!("{}: face-milling layer {} of {n}, top-down", sf.id, i + 1);
        out.features.push(MachiningFeature {
            id,
            owner: sf.id,
            shape: Prism {
                frame: PrismFrame {
                    origin: face,
                    x: g.fx,
                    z: g.n * s,
                },
                region: region.clone(),
                z_min: (lo - web_top) / c.abs(),
                z_max: (hi - web_top) / c.abs(),
            },
            side_adjacency: vec![Adjacency::Open; pts.len()],
            hole_adjacency: Vec::new(),
            bottom_adjacency: if (lo - web_top).abs() < EPS {
                Adjacency::Product
            } else {
                Adjacency::Feature
            },
            origin: FeatureOrigin {
                rule: rule.clone(),
                large: None,
            },
            access_blocked: false,
            slopes: None,
            provenance: prov,
        });
        let mut p = Provenance::new(ProvenanceSource::Knowledge, rule.clone())
            .with_value("layer_depth", b.layer_depth);
        p.note = format!("{}: face-milling layers top-down", sf.id);
        crate::extend_chain(out, &mut chain, id, p);
    }
    chain
}
