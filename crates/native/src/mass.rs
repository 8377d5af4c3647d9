//! Exact volume of a B-rep bounded by planes and cylinders (divergence
//! theorem: V = ⅓ Σ ∫ p·n dA), evaluated from the face loops alone.

use glam::DVec3;
use thinplan_brep::{Brep, Coedge, Curve, Surface};

/// (centre, axis of counter-clockwise travel, radius, sweep) of a circular coedge.
type ArcGeom = (DVec3, DVec3, f64, f64);

/// One coedge as (start, end, arc geometry if circular).
fn coedge_geom(b: &Brep, c: Coedge) -> (DVec3, DVec3, Option<ArcGeom>) {
    let e = &b.edges[c.edge];
    let (s, t) = (b.vertices[e.start].point, b.vertices[e.end].point);
    let (p, q) = if c.forward { (s, t) } else { (t, s) };
    match &e.curve {
        Curve::Circle { frame, radius } => {
            // Sweep along the curve from start to end in the edge's direction.
            let ang = |x: DVec3| {
                let d = x - frame.origin;
                d.dot(frame.y).atan2(d.dot(frame.x))
            };
            let tau = std::f64::consts::TAU;
            let mut sweep = if e.same_sense {
                (ang(t) - ang(s)).rem_euclid(tau)
            } else {
                (ang(s) - ang(t)).rem_euclid(tau)
            };
            if e.start == e.end || sweep < 1e-12 {
                sweep = tau;
            }
            // Axis about which the coedge travels counter-clockwise.
            let mut axis = if e.same_sense { frame.z } else { -frame.z };
            if !c.forward {
                axis = -axis;
            }
            (p, q, Some((frame.origin, axis, *radius, sweep)))
        }
        _ => (p, q, None),
    }
}

/// ∫ over a planar face of p·n_out dA = d · signed area.
fn plane_flux(b: &Brep, fi: usize) -> f64 {
    let f = &b.faces[fi];
    let Surface::Plane { frame } = &f.surface else {
        return 0.0;
    };
    let n = if f.same_sense { frame.z } else { -frame.z };
    // Vector area ½∮ p × dp, projected on n.
    let mut area = 0.0;
    for &l in &f.loops {
        for &c in &b.loops[l].coedges {
            let (p, q, arc) = coedge_geom(b, c);
            match arc {
                None => area += 0.5 * p.cross(q).dot(n),
                Some((centre, axis, r, sweep)) => {
                    // p(φ) = c + r(u cos φ + v sin φ), u towards p, v = axis × u.
                    let u = (p - centre).normalize();
                    let v = axis.cross(u);
                    // p × p' = r(−c×u sinφ + c×v cosφ) + r² u×v, integrated over the sweep.
                    let (s, co) = (sweep.sin(), sweep.cos());
                    let cu = centre.cross(u);
                    let cv = centre.cross(v);
                    let uv = u.cross(v);
                    let integral = r * (cu * (co - 1.0) + cv * s) + uv * (r * r * sweep);
                    area += 0.5 * integral.dot(n);
                }
            }
        }
    }
    frame.origin.dot(n) * area
}

/// ∫ over a cylindrical face of p·n_out dA, by Green's theorem in (θ, h):
/// ∫∫ f(θ) dθ dh = −∮ h f(θ) dθ, only circle edges contribute.
fn cylinder_flux(b: &Brep, fi: usize) -> f64 {
    let f = &b.faces[fi];
    let Surface::Cylinder { frame, radius } = &f.surface else {
        return 0.0;
    };
    let r = *radius;
    let (ox, oy) = (frame.origin.dot(frame.x), frame.origin.dot(frame.y));
    // f(θ) = r (o·u(θ) + r) with o the frame origin seen from the world origin;
    // antiderivative F(θ) = r (ox sinθ − oy cosθ + r θ).
    let big_f = |t: f64| r * (ox * t.sin() - oy * t.cos() + r * t);
    let mut total = 0.0;
    for &l in &f.loops {
        for &c in &b.loops[l].coedges {
            let (p, _, arc) = coedge_geom(b, c);
            let Some((centre, axis, _, sweep)) = arc else {
                continue;
            };
            let h = (centre - frame.origin).dot(frame.z);
            let d = p - frame.origin;
            let t0 = d.dot(frame.y).atan2(d.dot(frame.x));
            let dir = axis.dot(frame.z).signum();
            let t1 = t0 + dir * sweep;
            // The h·f integral of h ∫ f dθ over the edge.
            total -= h * (big_f(t1) - big_f(t0));
        }
    }
    // Orientation: loops run counter-clockwise about the outward normal;
    // (θ, h) is right-handed about the surface normal, so the sign works
    // out the same for both senses (see README).
    let _ = f.same_sense;
    total
}

/// Exact enclosed volume (planes and cylinders; other surfaces count zero).
pub fn volume(b: &Brep) -> f64 {
    let mut v = 0.0;
    for fi in 0..b.faces.len() {
        v += match b.faces[fi].surface {
            Surface::Plane { .. } => plane_flux(b, fi),
            Surface::Cylinder { .. } => cylinder_flux(b, fi),
            _ => 0.0,
        };
    }
    v / 3.0
}
