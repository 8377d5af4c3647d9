//! From touching prisms to one closed, manifold B-rep.
//!
//! 1. Every prism gives proto faces: two planar caps, a planar side per
//!    profile line, a cylindrical side per profile arc (one per full circle).
//! 2. Planar protos are grouped by carrier plane. In each plane, a 2D
//!    arrangement keeps what is covered by exactly one outward-up face and no
//!    outward-down face (and vice versa): contact faces cancel, touching
//!    faces with the same normal merge, a double cover is an overlap.
//! 3. Cylindrical protos on one cylinder with the same angular span and
//!    touching axial spans merge.
//! 4. Vertices are merged within the tolerance, every edge is split at the
//!    vertices lying on it (T-junctions), and equal edges are shared.
//! 5. The result is checked: every edge used twice in opposite directions,
//!    closed loops, one connected shell, and the exact volume equal to the
//!    sum of the prism volumes.

use std::collections::HashMap;

use glam::{DVec2, DVec3};
use thinplan_brep::{Brep, Coedge, Curve, Edge, Face, Frame, Loop, Shell, Solid, Surface};

use crate::arrange::{arrange, is_full_circle, ARegion, ArrangeError};
use crate::geom2::{reverse_loop, Seg};
use crate::geom3::{canon, circle_seam, Arc3, PointIndex3, Seg3};
use crate::profile::Region2;
use crate::NativeError;

/// A validated prism, ready to build.
#[derive(Debug, Clone)]
pub struct PrismGeo {
    pub id: String,
    pub frame: Frame,
    pub e0: f64,
    pub e1: f64,
    pub region: Region2,
    pub caps: (String, String),
}

impl PrismGeo {
    pub fn volume(&self) -> f64 {
        self.region.area() * (self.e1 - self.e0)
    }

    fn world(&self, p: DVec2, t: f64) -> DVec3 {
        self.frame.to_world(DVec3::new(p.x, p.y, t))
    }
}

/// A planar proto face: 3D loops with bulges about `ref_n`, region on the
/// left seen from `ref_n`; `out` is the outward normal.
struct PlaneProto {
    out: DVec3,
    point: DVec3,
    ref_n: DVec3,
    loops: Vec<Vec<(DVec3, DVec3, f64)>>,
    prism: usize,
    name: String,
}

/// A cylindrical proto face in its canonical cylinder frame.
#[derive(Debug, Clone)]
struct CylProto {
    origin: DVec3,
    axis: DVec3,
    radius: f64,
    sense: bool,
    /// (start angle, positive sweep) about `axis`; None = full circle.
    theta: Option<(f64, f64)>,
    h0: f64,
    h1: f64,
    prism: usize,
    name: String,
}

struct FaceOut {
    surface: Surface,
    same_sense: bool,
    loops: Vec<Vec<Seg3>>,
    name: String,
}

fn seg_name(p: &PrismGeo, name: &Option<String>) -> String {
    format!("{}.{}", p.id, name.as_deref().unwrap_or("side"))
}

fn cyl_key_frame(origin: DVec3, axis: DVec3) -> Frame {
    Frame::from_axis_ref(origin, axis, None)
}

fn angle_in(f: &Frame, p: DVec3) -> f64 {
    let d = p - f.origin;
    d.dot(f.y)
        .atan2(d.dot(f.x))
        .rem_euclid(std::f64::consts::TAU)
}

fn protos(prisms: &[PrismGeo], planes: &mut Vec<PlaneProto>, cyls: &mut Vec<CylProto>) {
    for (pi, p) in prisms.iter().enumerate() {
        let n = p.frame.z;
        // Caps: region loops CCW about n at both ends.
        let cap_loops = |t: f64| -> Vec<Vec<(DVec3, DVec3, f64)>> {
            p.region
                .loops()
                .map(|l| {
                    l.segs
                        .iter()
                        .map(|s| (p.world(s.a, t), p.world(s.b, t), s.bulge))
                        .collect()
                })
                .collect()
        };
        planes.push(PlaneProto {
            out: -n,
            point: p.world(DVec2::ZERO, p.e0),
            ref_n: n,
            loops: cap_loops(p.e0),
            prism: pi,
            name: format!("{}.{}", p.id, p.caps.0),
        });
        planes.push(PlaneProto {
            out: n,
            point: p.world(DVec2::ZERO, p.e1),
            ref_n: n,
            loops: cap_loops(p.e1),
            prism: pi,
            name: format!("{}.{}", p.id, p.caps.1),
        });
        for l in p.region.loops() {
            if l.circle {
                let (c, r) = l.segs[0].centre_radius();
                let c3 = p.world(c, 0.0);
                let axis = canon(n);
                let origin = c3 - axis * c3.dot(axis);
                let (h0, h1) = {
                    let a = (p.world(c, p.e0) - origin).dot(axis);
                    let b = (p.world(c, p.e1) - origin).dot(axis);
                    (a.min(b), a.max(b))
                };
                cyls.push(CylProto {
                    origin,
                    axis,
                    radius: r,
                    sense: l.segs[0].bulge > 0.0,
                    theta: None,
                    h0,
                    h1,
                    prism: pi,
                    name: seg_name(p, &l.names[0]),
                });
                continue;
            }
            for (k, s) in l.segs.iter().enumerate() {
                let name = seg_name(p, &l.names[k]);
                if s.is_line() {
                    let (a0, b0) = (p.world(s.a, p.e0), p.world(s.b, p.e0));
                    let (a1, b1) = (p.world(s.a, p.e1), p.world(s.b, p.e1));
                    let d = (b0 - a0).normalize();
                    let out = d.cross(n).normalize();
                    planes.push(PlaneProto {
                        out,
                        point: a0,
                        ref_n: out,
                        loops: vec![vec![
                            (a0, b0, 0.0),
                            (b0, b1, 0.0),
                            (b1, a1, 0.0),
                            (a1, a0, 0.0),
                        ]],
                        prism: pi,
                        name,
                    });
                } else {
                    let (c, r) = s.centre_radius();
                    let c3 = p.world(c, 0.0);
                    let axis = canon(n);
                    let origin = c3 - axis * c3.dot(axis);
                    let f = cyl_key_frame(origin, axis);
                    let ccw_about_axis = (s.bulge > 0.0) == (n.dot(axis) > 0.0);
                    let (pa, pb) = (p.world(s.a, 0.0), p.world(s.b, 0.0));
                    let start = if ccw_about_axis {
                        angle_in(&f, pa)
                    } else {
                        angle_in(&f, pb)
                    };
                    let (h0, h1) = {
                        let a = (p.world(c, p.e0) - origin).dot(axis);
                        let b = (p.world(c, p.e1) - origin).dot(axis);
                        (a.min(b), a.max(b))
                    };
                    cyls.push(CylProto {
                        origin,
                        axis,
                        radius: r,
                        sense: s.bulge > 0.0,
                        theta: Some((start, s.sweep().abs())),
                        h0,
                        h1,
                        prism: pi,
                        name,
                    });
                }
            }
        }
    }
}

fn err_shell(origin: &str, reason: String) -> NativeError {
    NativeError::InvalidShell {
        origin: origin.to_string(),
        reason,
    }
}

fn overlap_err(origin: &str, prisms: &[PrismGeo], ids: &[usize], at: String) -> NativeError {
    let mut names: Vec<&str> = ids.iter().map(|&i| prisms[i].id.as_str()).collect();
    names.dedup();
    let a = names.first().copied().unwrap_or("?").to_string();
    let b = names.get(1).copied().unwrap_or(a.as_str()).to_string();
    NativeError::Overlap {
        origin: origin.to_string(),
        a,
        b,
        reason: format!("faces on one plane cover each other {at}"),
    }
}

/// Planar faces: group by plane, cancel contacts, merge neighbours.
fn plane_faces(
    origin: &str,
    prisms: &[PrismGeo],
    protos: &[PlaneProto],
    tol: f64,
) -> Result<Vec<FaceOut>, NativeError> {
    struct Group {
        nc: DVec3,
        d: f64,
        members: Vec<usize>,
    }
    let mut groups: Vec<Group> = Vec::new();
    for (i, pp) in protos.iter().enumerate() {
        let nc = canon(pp.out);
        let d = nc.dot(pp.point);
        match groups
            .iter_mut()
            .find(|g| g.nc.dot(nc) > 1.0 - 1e-12 && (g.d - d).abs() <= tol)
        {
            Some(g) => g.members.push(i),
            None => groups.push(Group {
                nc,
                d,
                members: vec![i],
            }),
        }
    }
    let mut out = Vec::new();
    for g in &groups {
        let frame = Frame::from_axis_ref(g.nc * g.d, g.nc, None);
        let to2 = |p: DVec3| {
            let l = frame.to_local(p);
            DVec2::new(l.x, l.y)
        };
        let mut regions = Vec::new();
        for &m in &g.members {
            let pp = &protos[m];
            let flip = pp.ref_n.dot(g.nc) < 0.0;
            let loops = pp
                .loops
                .iter()
                .map(|l| {
                    let segs: Vec<Seg> = l
                        .iter()
                        .map(|&(a, b, k)| Seg {
                            a: to2(a),
                            b: to2(b),
                            bulge: if flip { -k } else { k },
                        })
                        .collect();
                    if flip {
                        reverse_loop(&segs)
                    } else {
                        segs
                    }
                })
                .collect();
            regions.push(ARegion {
                loops,
                class: if pp.out.dot(g.nc) > 0.0 { 0 } else { 1 },
            });
        }
        let valid = |c: &[u32]| c[0] <= 1 && c[1] <= 1;
        for class in 0..2usize {
            if !regions.iter().any(|r| r.class == class) {
                continue;
            }
            let inside = move |c: &[u32]| c[class] == 1 && c[1 - class] == 0;
            let faces = arrange(&regions, 2, tol, &inside, &valid).map_err(|e| match e {
                ArrangeError::Invalid { regions: rs, at } => {
                    let ids: Vec<usize> = rs.iter().map(|&r| protos[g.members[r]].prism).collect();
                    let p3 = frame.to_world(DVec3::new(at.x, at.y, 0.0));
                    overlap_err(
                        origin,
                        prisms,
                        &ids,
                        format!("near ({:.4}, {:.4}, {:.4})", p3.x, p3.y, p3.z),
                    )
                }
                ArrangeError::Topology(s) => err_shell(origin, s),
            })?;
            for f in faces {
                // Merged faces carry every contributing name, in prism order.
                let mut contrib: Vec<usize> = f
                    .cover
                    .iter()
                    .filter(|&&r| regions[r].class == class)
                    .map(|&r| g.members[r])
                    .collect();
                contrib.sort_unstable();
                contrib.dedup();
                let mut names: Vec<&str> = Vec::new();
                for m in contrib {
                    if !names.contains(&protos[m].name.as_str()) {
                        names.push(&protos[m].name);
                    }
                }
                let name = names.join("+");
                let sign = if class == 0 { 1.0 } else { -1.0 };
                let mut loops = Vec::new();
                for l in std::iter::once(&f.outer).chain(f.holes.iter()) {
                    let l: Vec<Seg> = if class == 0 {
                        l.clone()
                    } else {
                        reverse_loop(l)
                    };
                    loops.push(loop_to_3d(&frame, &l, tol));
                }
                let _ = sign;
                out.push(FaceOut {
                    surface: Surface::Plane { frame },
                    same_sense: class == 0,
                    loops,
                    name,
                });
            }
        }
    }
    Ok(out)
}

/// A 2D loop in `frame`'s plane to 3D segments (full circles become one closed edge).
fn loop_to_3d(frame: &Frame, l: &[Seg], tol: f64) -> Vec<Seg3> {
    let w = |p: DVec2| frame.to_world(DVec3::new(p.x, p.y, 0.0));
    if let Some((c, r, ccw)) = is_full_circle(l, tol) {
        let centre = w(c);
        let axis = if ccw { frame.z } else { -frame.z };
        let seam = circle_seam(centre, axis, r);
        return vec![Seg3 {
            a: seam,
            b: seam,
            arc: Some(Arc3 {
                centre,
                axis,
                radius: r,
                full: true,
            }),
        }];
    }
    l.iter()
        .map(|s| {
            if s.is_line() {
                Seg3::line(w(s.a), w(s.b))
            } else {
                let (c, r) = s.centre_radius();
                Seg3 {
                    a: w(s.a),
                    b: w(s.b),
                    arc: Some(Arc3 {
                        centre: w(c),
                        axis: if s.bulge > 0.0 { frame.z } else { -frame.z },
                        radius: r,
                        full: false,
                    }),
                }
            }
        })
        .collect()
}

fn same_theta(a: Option<(f64, f64)>, b: Option<(f64, f64)>) -> bool {
    match (a, b) {
        (None, None) => true,
        (Some((s1, w1)), Some((s2, w2))) => {
            let ds = (s1 - s2).rem_euclid(std::f64::consts::TAU);
            !(1e-9..=std::f64::consts::TAU - 1e-9).contains(&ds) && (w1 - w2).abs() < 1e-9
        }
        _ => false,
    }
}

fn thetas_overlap(a: Option<(f64, f64)>, b: Option<(f64, f64)>) -> bool {
    match (a, b) {
        (Some((s1, w1)), Some((s2, w2))) => {
            // Interval overlap on the circle, with a small margin.
            let tau = std::f64::consts::TAU;
            let d = (s2 - s1).rem_euclid(tau);
            let e = (s1 - s2).rem_euclid(tau);
            d < w1 - 1e-9 || e < w2 - 1e-9
        }
        _ => true,
    }
}

/// Cylindrical faces: merge axially touching pieces of one cylinder.
fn cylinder_faces(
    origin: &str,
    prisms: &[PrismGeo],
    mut cyls: Vec<CylProto>,
    tol: f64,
) -> Result<Vec<FaceOut>, NativeError> {
    let same_cyl = |a: &CylProto, b: &CylProto| {
        a.axis.dot(b.axis) > 1.0 - 1e-12
            && a.origin.distance(b.origin) <= tol
            && (a.radius - b.radius).abs() <= tol
    };
    // Overlaps between pieces of one cylinder (same or opposite sense).
    for i in 0..cyls.len() {
        for j in i + 1..cyls.len() {
            let (a, b) = (&cyls[i], &cyls[j]);
            if same_cyl(a, b)
                && a.h0 < b.h1 - tol
                && b.h0 < a.h1 - tol
                && thetas_overlap(a.theta, b.theta)
            {
                return Err(NativeError::Overlap {
                    origin: origin.to_string(),
                    a: prisms[a.prism].id.clone(),
                    b: prisms[b.prism].id.clone(),
                    reason: format!(
                        "faces `{}` and `{}` lie on one cylinder (contact on curved faces is not supported)",
                        a.name, b.name
                    ),
                });
            }
        }
    }
    cyls.sort_by(|a, b| a.h0.total_cmp(&b.h0));
    let mut merged = true;
    while merged {
        merged = false;
        'outer: for i in 0..cyls.len() {
            for j in 0..cyls.len() {
                if i == j {
                    continue;
                }
                let (a, b) = (&cyls[i], &cyls[j]);
                if same_cyl(a, b)
                    && a.sense == b.sense
                    && same_theta(a.theta, b.theta)
                    && (a.h1 - b.h0).abs() <= tol
                {
                    let h1 = b.h1;
                    cyls[i].h1 = h1;
                    cyls.remove(j);
                    merged = true;
                    break 'outer;
                }
            }
        }
    }
    let mut out = Vec::new();
    for c in cyls {
        let f = cyl_key_frame(c.origin, c.axis);
        let at = |ang: f64, h: f64| {
            c.origin + c.axis * h + (f.x * ang.cos() + f.y * ang.sin()) * c.radius
        };
        let arc = |full: bool, h: f64, up: bool| Arc3 {
            centre: c.origin + c.axis * h,
            axis: if up { c.axis } else { -c.axis },
            radius: c.radius,
            full,
        };
        let loops = match c.theta {
            None => {
                let (bot, top) = (c.origin + c.axis * c.h0, c.origin + c.axis * c.h1);
                let sb = circle_seam(bot, c.axis, c.radius);
                let st = circle_seam(top, c.axis, c.radius);
                let b = Seg3 {
                    a: sb,
                    b: sb,
                    arc: Some(arc(true, c.h0, c.sense)),
                };
                let t = Seg3 {
                    a: st,
                    b: st,
                    arc: Some(arc(true, c.h1, !c.sense)),
                };
                vec![vec![b], vec![t]]
            }
            Some((s, w)) => {
                let (p00, p10) = (at(s, c.h0), at(s + w, c.h0));
                let (p01, p11) = (at(s, c.h1), at(s + w, c.h1));
                let l = vec![
                    Seg3 {
                        a: p00,
                        b: p10,
                        arc: Some(arc(false, c.h0, true)),
                    },
                    Seg3::line(p10, p11),
                    Seg3 {
                        a: p11,
                        b: p01,
                        arc: Some(arc(false, c.h1, false)),
                    },
                    Seg3::line(p01, p00),
                ];
                if c.sense {
                    vec![l]
                } else {
                    vec![l.iter().rev().map(Seg3::reversed).collect()]
                }
            }
        };
        out.push(FaceOut {
            surface: Surface::Cylinder {
                frame: f,
                radius: c.radius,
            },
            same_sense: c.sense,
            loops,
            name: c.name,
        });
    }
    Ok(out)
}

fn geom_matches(e: &Seg3, s: &Seg3, tol: f64) -> bool {
    match (e.arc, s.arc) {
        (None, None) => true,
        (Some(a), Some(b)) => {
            a.centre.distance(b.centre) <= tol * 10.0
                && (a.radius - b.radius).abs() <= tol * 10.0
                && a.axis.dot(b.axis).abs() > 1.0 - 1e-9
                && (a.full || e.midpoint().distance(s.midpoint()) <= tol * 10.0)
        }
        _ => false,
    }
}

/// Builds the B-rep of touching prisms and checks it.
pub fn build(origin: &str, name: &str, prisms: &[PrismGeo], tol: f64) -> Result<Brep, NativeError> {
    let mut pp = Vec::new();
    let mut cp = Vec::new();
    protos(prisms, &mut pp, &mut cp);
    let mut faces = plane_faces(origin, prisms, &pp, tol)?;
    faces.extend(cylinder_faces(origin, prisms, cp, tol)?);

    // Vertices.
    let mut index = PointIndex3::new(tol);
    for f in &faces {
        for l in &f.loops {
            for s in l {
                index.id(s.a);
                index.id(s.b);
            }
        }
    }
    let verts = index.pts.clone();
    let mut by_x: Vec<usize> = (0..verts.len()).collect();
    by_x.sort_by(|&a, &b| verts[a].x.total_cmp(&verts[b].x));
    let xs: Vec<f64> = by_x.iter().map(|&i| verts[i].x).collect();

    let mut brep = Brep::new();
    for p in &verts {
        brep.add_vertex(*p);
    }
    let mut edge_geo: Vec<Seg3> = Vec::new();
    let mut by_ends: HashMap<(usize, usize), Vec<usize>> = HashMap::new();
    let mut uses: Vec<(u32, u32)> = Vec::new();
    let mut face_ids = Vec::new();
    for f in &faces {
        let mut loop_ids = Vec::new();
        for (li, l) in f.loops.iter().enumerate() {
            let mut coedges = Vec::new();
            for s in l {
                // T-junctions: vertices inside this segment.
                let (lo, hi) = s.bounds();
                let from = xs.partition_point(|&x| x < lo.x - tol);
                let mut cuts: Vec<(f64, DVec3)> = Vec::new();
                for &vi in &by_x[from..] {
                    let p = verts[vi];
                    if p.x > hi.x + tol {
                        break;
                    }
                    if p.y < lo.y - tol || p.y > hi.y + tol || p.z < lo.z - tol || p.z > hi.z + tol
                    {
                        continue;
                    }
                    if let Some(t) = s.interior_param(p, tol) {
                        cuts.push((t, p));
                    }
                }
                cuts.sort_by(|a, b| a.0.total_cmp(&b.0));
                for piece in s.split(&cuts) {
                    let va = index.id(piece.a);
                    let vb = index.id(piece.b);
                    if va == vb && piece.arc.is_none_or(|a| !a.full) {
                        continue;
                    }
                    let key = (va.min(vb), va.max(vb));
                    let list = by_ends.entry(key).or_default();
                    let found = list
                        .iter()
                        .copied()
                        .find(|&e| geom_matches(&edge_geo[e], &piece, tol));
                    let (edge, forward) = match found {
                        Some(e) => {
                            let fwd = if va == vb {
                                let ea = edge_geo[e].arc.expect("arc").axis;
                                piece.arc.expect("arc").axis.dot(ea) > 0.0
                            } else {
                                brep.edges[e].start == va
                            };
                            (e, fwd)
                        }
                        None => {
                            let curve = match piece.arc {
                                None => Curve::Line {
                                    origin: piece.a,
                                    dir: (piece.b - piece.a).normalize(),
                                },
                                Some(a) => {
                                    let x = (piece.a - a.centre).normalize();
                                    Curve::Circle {
                                        frame: Frame {
                                            origin: a.centre,
                                            x,
                                            y: a.axis.cross(x),
                                            z: a.axis,
                                        },
                                        radius: a.radius,
                                    }
                                }
                            };
                            let e = brep.add_edge(Edge {
                                start: va,
                                end: vb,
                                curve,
                                same_sense: true,
                            });
                            edge_geo.push(piece);
                            uses.push((0, 0));
                            list.push(e);
                            (e, true)
                        }
                    };
                    if forward {
                        uses[edge].0 += 1;
                    } else {
                        uses[edge].1 += 1;
                    }
                    coedges.push(Coedge { edge, forward });
                }
            }
            loop_ids.push(brep.add_loop(Loop {
                coedges,
                vertex: None,
                orientation: true,
                outer: li == 0,
            }));
        }
        face_ids.push(brep.add_face(Face {
            surface: f.surface.clone(),
            same_sense: f.same_sense,
            loops: loop_ids,
            name: f.name.clone(),
        }));
    }
    let shell = brep.add_shell(Shell {
        faces: face_ids,
        closed: true,
    });
    brep.add_solid(Solid {
        shells: vec![shell],
        name: name.to_string(),
    });

    // Checks.
    for (e, &(f, b)) in uses.iter().enumerate() {
        if f != 1 || b != 1 {
            let edge = &brep.edges[e];
            let (p, q) = (verts[edge.start], verts[edge.end]);
            let users: Vec<&str> = brep
                .faces
                .iter()
                .filter(|fc| {
                    fc.loops
                        .iter()
                        .any(|&l| brep.loops[l].coedges.iter().any(|c| c.edge == e))
                })
                .map(|fc| fc.name.as_str())
                .collect();
            let what = if f + b == 1 {
                "open shell: an edge is used by one face only".to_string()
            } else if f + b == 2 {
                "faces meeting at an edge are inconsistently oriented".to_string()
            } else {
                format!("non-manifold edge used by {} faces (prisms touching along an edge only, or overlapping?)", f + b)
            };
            return Err(err_shell(
                origin,
                format!(
                    "{what}: edge ({:.4}, {:.4}, {:.4})–({:.4}, {:.4}, {:.4}), faces {:?}",
                    p.x, p.y, p.z, q.x, q.y, q.z, users
                ),
            ));
        }
    }
    crate::check::check_solid(&brep).map_err(|r| err_shell(origin, r))?;
    Ok(brep)
}
