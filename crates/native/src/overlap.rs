//! Pairwise interference check of prisms (they may touch, never overlap).
//!
//! Parallel prisms overlap when their extents overlap and their profiles,
//! seen in one frame, share area. Perpendicular prisms A and B (normals nA,
//! nB, common direction w = nA × nB) overlap exactly when the projection on
//! w of (A's profile ∩ B's slab) and of (B's profile ∩ A's slab) share an
//! interval of positive length. Other angles are not supported.

use glam::{DVec2, DVec3};

use crate::arrange::{arrange, ARegion};
use crate::build::PrismGeo;
use crate::geom2::{reverse_loop, Seg};
use crate::NativeError;

fn aabb(p: &PrismGeo) -> (DVec3, DVec3) {
    let (lo, hi) = p.region.bounds();
    let mut a = DVec3::splat(f64::INFINITY);
    let mut b = DVec3::splat(f64::NEG_INFINITY);
    for x in [lo.x, hi.x] {
        for y in [lo.y, hi.y] {
            for t in [p.e0, p.e1] {
                let q = p.frame.to_world(DVec3::new(x, y, t));
                a = a.min(q);
                b = b.max(q);
            }
        }
    }
    (a, b)
}

/// The prism's profile mapped by `map` (profile point → 2D), with loops kept
/// region-on-left (reversed when the map mirrors).
fn mapped_loops(p: &PrismGeo, map: &dyn Fn(DVec2) -> DVec2) -> Vec<Vec<Seg>> {
    let o = map(DVec2::ZERO);
    let ex = map(DVec2::X) - o;
    let ey = map(DVec2::Y) - o;
    let mirror = ex.perp_dot(ey) < 0.0;
    p.region
        .loops()
        .map(|l| {
            let segs: Vec<Seg> = l
                .segs
                .iter()
                .map(|s| Seg {
                    a: map(s.a),
                    b: map(s.b),
                    bulge: if mirror { -s.bulge } else { s.bulge },
                })
                .collect();
            if mirror {
                reverse_loop(&segs)
            } else {
                segs
            }
        })
        .collect()
}

fn both(c: &[u32]) -> bool {
    c[0] >= 1 && c[1] >= 1
}

fn any(_: &[u32]) -> bool {
    true
}

fn rect(lo: DVec2, hi: DVec2) -> Vec<Seg> {
    let p = [lo, DVec2::new(hi.x, lo.y), hi, DVec2::new(lo.x, hi.y)];
    (0..4).map(|i| Seg::line(p[i], p[(i + 1) % 4])).collect()
}

/// γ-intervals of (profile ∩ slab β ∈ [b0, b1]) for a profile in (β, γ).
fn slab_intervals(loops: Vec<Vec<Seg>>, b0: f64, b1: f64, tol: f64) -> Vec<(f64, f64)> {
    let (mut lo, mut hi) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
    for l in &loops {
        for s in l {
            let (a, b) = s.bounds();
            lo = lo.min(a);
            hi = hi.max(b);
        }
    }
    let strip = rect(DVec2::new(b0, lo.y - 1.0), DVec2::new(b1, hi.y + 1.0));
    let regions = [
        ARegion { loops, class: 0 },
        ARegion {
            loops: vec![strip],
            class: 1,
        },
    ];
    match arrange(&regions, 2, tol, &both, &any) {
        Ok(faces) => faces
            .iter()
            .filter(|f| f.area() > tol * tol)
            .map(|f| {
                let (lo, hi) = crate::geom2::loop_bounds(&f.outer);
                (lo.y, hi.y)
            })
            .collect(),
        // Numerical trouble: be conservative and report the whole range.
        Err(_) => vec![(lo.y, hi.y)],
    }
}

pub fn check_overlaps(origin: &str, prisms: &[PrismGeo], tol: f64) -> Result<(), NativeError> {
    let boxes: Vec<_> = prisms.iter().map(aabb).collect();
    for i in 0..prisms.len() {
        for j in i + 1..prisms.len() {
            let ((alo, ahi), (blo, bhi)) = (boxes[i], boxes[j]);
            let ov = ahi.min(bhi) - alo.max(blo);
            if ov.x <= tol || ov.y <= tol || ov.z <= tol {
                continue;
            }
            let (a, b) = (&prisms[i], &prisms[j]);
            let (na, nb) = (a.frame.z, b.frame.z);
            let dot = na.dot(nb);
            let overlap = |reason: String| NativeError::Overlap {
                origin: origin.to_string(),
                a: a.id.clone(),
                b: b.id.clone(),
                reason,
            };
            if dot.abs() > 1.0 - 1e-9 {
                // Extents along na.
                let sa = (a.frame.origin.dot(na) + a.e0, a.frame.origin.dot(na) + a.e1);
                let ob = b.frame.origin.dot(na);
                let sb = if dot > 0.0 {
                    (ob + b.e0, ob + b.e1)
                } else {
                    (ob - b.e1, ob - b.e0)
                };
                if sa.1.min(sb.1) - sa.0.max(sb.0) <= tol {
                    continue;
                }
                let ident = |p: DVec2| p;
                let to_a = |p: DVec2| {
                    let w = b.frame.to_world(DVec3::new(p.x, p.y, 0.0));
                    let l = a.frame.to_local(w);
                    DVec2::new(l.x, l.y)
                };
                let regions = [
                    ARegion {
                        loops: mapped_loops(a, &ident),
                        class: 0,
                    },
                    ARegion {
                        loops: mapped_loops(b, &to_a),
                        class: 1,
                    },
                ];
                let area: f64 = match arrange(&regions, 2, tol, &both, &any) {
                    Ok(faces) => faces.iter().map(|f| f.area()).sum(),
                    Err(_) => f64::INFINITY,
                };
                if area > tol * tol * 100.0 {
                    return Err(overlap(format!(
                        "parallel prisms whose profiles share {area:.4} mm² over a common extent"
                    )));
                }
            } else if dot.abs() < 1e-9 {
                let w = na.cross(nb).normalize();
                let map_a = |p: DVec2| {
                    let q = a.frame.to_world(DVec3::new(p.x, p.y, 0.0));
                    DVec2::new(q.dot(nb), q.dot(w))
                };
                let map_b = |p: DVec2| {
                    let q = b.frame.to_world(DVec3::new(p.x, p.y, 0.0));
                    DVec2::new(q.dot(na), q.dot(w))
                };
                let slab_b = (b.frame.origin.dot(nb) + b.e0, b.frame.origin.dot(nb) + b.e1);
                let slab_a = (a.frame.origin.dot(na) + a.e0, a.frame.origin.dot(na) + a.e1);
                let ia = slab_intervals(mapped_loops(a, &map_a), slab_b.0, slab_b.1, tol);
                if ia.is_empty() {
                    continue;
                }
                let ib = slab_intervals(mapped_loops(b, &map_b), slab_a.0, slab_a.1, tol);
                for x in &ia {
                    for y in &ib {
                        let len = x.1.min(y.1) - x.0.max(y.0);
                        if len > tol {
                            return Err(overlap(format!(
                                "perpendicular prisms share volume (over {len:.4} mm along their common direction)"
                            )));
                        }
                    }
                }
            } else {
                return Err(NativeError::Unsupported {
                    origin: origin.to_string(),
                    reason: format!(
                        "prisms `{}` and `{}` meet at {:.2}°; only parallel or perpendicular \
                         prisms can be checked for overlap",
                        a.id,
                        b.id,
                        dot.abs().acos().to_degrees()
                    ),
                });
            }
        }
    }
    Ok(())
}
