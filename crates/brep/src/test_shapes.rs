//! Hand-built B-reps for tests: prisms extruded from planar profiles (boxes,
//! L-prisms, plates with round holes and slots), cylinders (with and without
//! a seam edge), a cone with an apex vertex loop and a hemisphere.
//!
//! Built like STEP files written by CAD systems: every edge is used once in
//! each direction, loops run counter-clockwise about the outward normal,
//! round holes are bounded by closed circle edges with `same_sense = false`
//! and cylindrical hole faces have `same_sense = false`.
//!
//! Available to other crates with the `test-shapes` feature.

use std::f64::consts::{PI, TAU};

use glam::{DVec2, DVec3};

use crate::geom::{Curve, Frame, Surface};
use crate::{Brep, Coedge, Edge, Face, FaceId, Loop, Shell, Solid};

/// The kind of a profile segment running to the next profile point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Seg {
    Line,
    /// A circular arc about `center`, counter-clockwise (seen from +z) when `ccw`.
    Arc {
        center: DVec2,
        ccw: bool,
    },
}

/// A closed planar profile in the xy plane.
#[derive(Debug, Clone, PartialEq)]
pub enum Profile {
    /// Each entry is a point and the segment from it to the next entry.
    Path(Vec<(DVec2, Seg)>),
    /// A full circle (bounded by one closed edge).
    Circle { center: DVec2, radius: f64 },
}

impl Profile {
    pub fn polygon(pts: &[DVec2]) -> Profile {
        Profile::Path(pts.iter().map(|&p| (p, Seg::Line)).collect())
    }

    pub fn rect(min: DVec2, max: DVec2) -> Profile {
        Profile::polygon(&[min, DVec2::new(max.x, min.y), max, DVec2::new(min.x, max.y)])
    }

    /// A slot (stadium): straight sides of length `2 * half_len` along x,
    /// round ends of radius `r`.
    pub fn stadium(center: DVec2, half_len: f64, r: f64) -> Profile {
        let c1 = center + DVec2::new(half_len, 0.0);
        let c0 = center - DVec2::new(half_len, 0.0);
        Profile::Path(vec![
            (c0 - DVec2::new(0.0, r), Seg::Line),
            (
                c1 - DVec2::new(0.0, r),
                Seg::Arc {
                    center: c1,
                    ccw: true,
                },
            ),
            (c1 + DVec2::new(0.0, r), Seg::Line),
            (
                c0 + DVec2::new(0.0, r),
                Seg::Arc {
                    center: c0,
                    ccw: true,
                },
            ),
        ])
    }

    /// Signed area (positive counter-clockwise), exact for arcs.
    pub fn signed_area(&self) -> f64 {
        match self {
            Profile::Circle { radius, .. } => PI * radius * radius,
            Profile::Path(v) => {
                let n = v.len();
                let mut a = 0.0;
                for i in 0..n {
                    let (p, seg) = v[i];
                    let q = v[(i + 1) % n].0;
                    a += 0.5 * p.perp_dot(q);
                    if let Seg::Arc { center, ccw } = seg {
                        let r = (p - center).length();
                        let sweep = arc_sweep(p, q, center, ccw);
                        let seg_area = 0.5 * r * r * (sweep - sweep.sin());
                        a += if ccw { seg_area } else { -seg_area };
                    }
                }
                a
            }
        }
    }

    /// Perimeter, exact for arcs.
    pub fn perimeter(&self) -> f64 {
        match self {
            Profile::Circle { radius, .. } => TAU * radius,
            Profile::Path(v) => {
                let n = v.len();
                (0..n)
                    .map(|i| {
                        let (p, seg) = v[i];
                        let q = v[(i + 1) % n].0;
                        match seg {
                            Seg::Line => p.distance(q),
                            Seg::Arc { center, ccw } => {
                                (p - center).length() * arc_sweep(p, q, center, ccw)
                            }
                        }
                    })
                    .sum()
            }
        }
    }

    /// The same profile traversed the other way.
    pub fn reversed(&self) -> Profile {
        match self {
            Profile::Circle { .. } => self.clone(),
            Profile::Path(v) => {
                let n = v.len();
                Profile::Path(
                    (0..n)
                        .rev()
                        .map(|i| {
                            let seg = match v[i].1 {
                                Seg::Line => Seg::Line,
                                Seg::Arc { center, ccw } => Seg::Arc { center, ccw: !ccw },
                            };
                            (v[(i + 1) % n].0, seg)
                        })
                        .collect(),
                )
            }
        }
    }
}

/// Positive sweep angle of an arc from `p` to `q` about `c`.
fn arc_sweep(p: DVec2, q: DVec2, c: DVec2, ccw: bool) -> f64 {
    let a0 = (p - c).to_angle();
    let a1 = (q - c).to_angle();
    let mut s = if ccw { a1 - a0 } else { a0 - a1 };
    while s <= 1e-12 {
        s += TAU;
    }
    while s > TAU + 1e-12 {
        s -= TAU;
    }
    s
}

fn v3(p: DVec2, z: f64) -> DVec3 {
    DVec3::new(p.x, p.y, z)
}

fn lp(coedges: Vec<Coedge>, outer: bool) -> Loop {
    Loop {
        coedges,
        vertex: None,
        orientation: true,
        outer,
    }
}

fn ce(edge: usize, forward: bool) -> Coedge {
    Coedge { edge, forward }
}

/// Builds the edges and side faces of one profile; returns the loops of the
/// bottom face and of the top face. `material_left`: the profile runs with
/// the material on its left (outer profiles CCW, holes CW).
fn build_profile(
    b: &mut Brep,
    prof: &Profile,
    h: f64,
    outer: bool,
    seam: bool,
    sides: &mut Vec<FaceId>,
) -> (Loop, Loop) {
    match prof {
        Profile::Circle { center, radius } => {
            // Outer circles run CCW (material inside); holes run CW.
            let ccw = outer;
            let p0 = *center + DVec2::new(*radius, 0.0);
            let bv = b.add_vertex(v3(p0, 0.0));
            let tv = b.add_vertex(v3(p0, h));
            let circle = |z: f64| Curve::Circle {
                frame: Frame::from_axis_ref(v3(*center, z), DVec3::Z, Some(DVec3::X)),
                radius: *radius,
            };
            let be = b.add_edge(Edge {
                start: bv,
                end: bv,
                curve: circle(0.0),
                same_sense: ccw,
            });
            let te = b.add_edge(Edge {
                start: tv,
                end: tv,
                curve: circle(h),
                same_sense: ccw,
            });
            let surface = Surface::Cylinder {
                frame: Frame::from_axis_ref(v3(*center, 0.0), DVec3::Z, Some(DVec3::X)),
                radius: *radius,
            };
            let loops = if seam {
                let se = b.add_edge(Edge {
                    start: bv,
                    end: tv,
                    curve: Curve::Line {
                        origin: v3(p0, 0.0),
                        dir: DVec3::Z,
                    },
                    same_sense: true,
                });
                let l = b.add_loop(lp(
                    vec![ce(be, true), ce(se, true), ce(te, false), ce(se, false)],
                    true,
                ));
                vec![l]
            } else {
                vec![
                    b.add_loop(lp(vec![ce(be, true)], true)),
                    b.add_loop(lp(vec![ce(te, false)], false)),
                ]
            };
            sides.push(b.add_face(Face {
                surface,
                same_sense: ccw,
                loops,
                name: String::new(),
            }));
            (
                lp(vec![ce(be, false)], outer),
                lp(vec![ce(te, true)], outer),
            )
        }
        Profile::Path(v) => {
            let n = v.len();
            let bv: Vec<usize> = v.iter().map(|(p, _)| b.add_vertex(v3(*p, 0.0))).collect();
            let tv: Vec<usize> = v.iter().map(|(p, _)| b.add_vertex(v3(*p, h))).collect();
            let mut be = Vec::with_capacity(n);
            let mut te = Vec::with_capacity(n);
            for i in 0..n {
                let j = (i + 1) % n;
                let (p, seg) = v[i];
                let q = v[j].0;
                for (z, verts, out) in [(0.0, &bv, &mut be), (h, &tv, &mut te)] {
                    let (curve, same_sense) = match seg {
                        Seg::Line => (
                            Curve::Line {
                                origin: v3(p, z),
                                dir: v3(q - p, 0.0).normalize(),
                            },
                            true,
                        ),
                        Seg::Arc { center, ccw } => (
                            Curve::Circle {
                                frame: Frame::from_axis_ref(
                                    v3(center, z),
                                    DVec3::Z,
                                    Some(DVec3::X),
                                ),
                                radius: (p - center).length(),
                            },
                            ccw,
                        ),
                    };
                    out.push(b.add_edge(Edge {
                        start: verts[i],
                        end: verts[j],
                        curve,
                        same_sense,
                    }));
                }
            }
            let ve: Vec<usize> = (0..n)
                .map(|i| {
                    b.add_edge(Edge {
                        start: bv[i],
                        end: tv[i],
                        curve: Curve::Line {
                            origin: v3(v[i].0, 0.0),
                            dir: DVec3::Z,
                        },
                        same_sense: true,
                    })
                })
                .collect();
            for i in 0..n {
                let j = (i + 1) % n;
                let (p, seg) = v[i];
                let q = v[j].0;
                let (surface, same_sense) = match seg {
                    Seg::Line => {
                        let d = v3(q - p, 0.0).normalize();
                        let nrm = d.cross(DVec3::Z);
                        // Alternate the plane's own normal to exercise same_sense.
                        if i % 2 == 0 {
                            (
                                Surface::Plane {
                                    frame: Frame::from_axis_ref(v3(p, 0.0), nrm, Some(d)),
                                },
                                true,
                            )
                        } else {
                            (
                                Surface::Plane {
                                    frame: Frame::from_axis_ref(v3(p, 0.0), -nrm, Some(d)),
                                },
                                false,
                            )
                        }
                    }
                    Seg::Arc { center, ccw } => (
                        Surface::Cylinder {
                            frame: Frame::from_axis_ref(v3(center, 0.0), DVec3::Z, Some(DVec3::X)),
                            radius: (p - center).length(),
                        },
                        ccw,
                    ),
                };
                let l = b.add_loop(lp(
                    vec![
                        ce(be[i], true),
                        ce(ve[j], true),
                        ce(te[i], false),
                        ce(ve[i], false),
                    ],
                    true,
                ));
                sides.push(b.add_face(Face {
                    surface,
                    same_sense,
                    loops: vec![l],
                    name: String::new(),
                }));
            }
            (
                lp((0..n).rev().map(|i| ce(be[i], false)).collect(), outer),
                lp((0..n).map(|i| ce(te[i], true)).collect(), outer),
            )
        }
    }
}

fn extrude_impl(outer: &Profile, holes: &[Profile], h: f64, seam: bool) -> Brep {
    let mut b = Brep::new();
    let mut sides = Vec::new();
    let outer = if outer.signed_area() < 0.0 {
        outer.reversed()
    } else {
        outer.clone()
    };
    let mut bottom_loops = Vec::new();
    let mut top_loops = Vec::new();
    let (bl, tl) = build_profile(&mut b, &outer, h, true, seam, &mut sides);
    bottom_loops.push(bl);
    top_loops.push(tl);
    for hole in holes {
        let hole = if hole.signed_area() > 0.0 && !matches!(hole, Profile::Circle { .. }) {
            hole.reversed()
        } else {
            hole.clone()
        };
        let (bl, tl) = build_profile(&mut b, &hole, h, false, seam, &mut sides);
        bottom_loops.push(bl);
        top_loops.push(tl);
    }
    let bottom_loops = bottom_loops.into_iter().map(|l| b.add_loop(l)).collect();
    let top_loops = top_loops.into_iter().map(|l| b.add_loop(l)).collect();
    let bottom = b.add_face(Face {
        surface: Surface::Plane {
            frame: Frame::WORLD,
        },
        same_sense: false,
        loops: bottom_loops,
        name: "bottom".into(),
    });
    let top = b.add_face(Face {
        surface: Surface::Plane {
            frame: Frame::from_axis_ref(DVec3::new(0.0, 0.0, h), DVec3::Z, Some(DVec3::X)),
        },
        same_sense: true,
        loops: top_loops,
        name: "top".into(),
    });
    let mut faces = vec![bottom, top];
    faces.extend(sides);
    let shell = b.add_shell(Shell {
        faces,
        closed: true,
    });
    b.add_solid(Solid {
        shells: vec![shell],
        name: "prism".into(),
    });
    b
}

/// A prism: `outer` (any orientation) minus `holes`, extruded from z = 0 to `h`.
pub fn extrude(outer: &Profile, holes: &[Profile], h: f64) -> Brep {
    extrude_impl(outer, holes, h, false)
}

/// As [`extrude`], but round holes/cylinders get a seam edge and a single loop
/// (as OpenCASCADE writes full cylinders).
pub fn extrude_with_seams(outer: &Profile, holes: &[Profile], h: f64) -> Brep {
    extrude_impl(outer, holes, h, true)
}

/// Axis-aligned box `[0,dx]×[0,dy]×[0,dz]`.
pub fn box_shape(dx: f64, dy: f64, dz: f64) -> Brep {
    extrude(&Profile::rect(DVec2::ZERO, DVec2::new(dx, dy)), &[], dz)
}

/// Box `[0,dx]×[0,dy]×[0,dz]` with a round through-hole along z.
pub fn box_with_hole(dx: f64, dy: f64, dz: f64, center: DVec2, r: f64) -> Brep {
    extrude(
        &Profile::rect(DVec2::ZERO, DVec2::new(dx, dy)),
        &[Profile::Circle { center, radius: r }],
        dz,
    )
}

/// Plate `[0,w]×[0,l]×[0,t]` with round through-holes `(center, radius)`.
pub fn plate_with_holes(w: f64, l: f64, t: f64, holes: &[(DVec2, f64)]) -> Brep {
    let holes: Vec<Profile> = holes
        .iter()
        .map(|&(center, radius)| Profile::Circle { center, radius })
        .collect();
    extrude(&Profile::rect(DVec2::ZERO, DVec2::new(w, l)), &holes, t)
}

/// An L-shaped prism: legs `a` (along x) and `b` (along y), wall thickness
/// `t`, height `h`. Its inner vertical edge at `(t, t)` is concave.
pub fn l_prism(a: f64, b: f64, t: f64, h: f64) -> Brep {
    extrude(
        &Profile::polygon(&[
            DVec2::new(0.0, 0.0),
            DVec2::new(a, 0.0),
            DVec2::new(a, t),
            DVec2::new(t, t),
            DVec2::new(t, b),
            DVec2::new(0.0, b),
        ]),
        &[],
        h,
    )
}

/// A solid cylinder of radius `r` about the z axis, from z = 0 to `h`,
/// its side bounded by two closed circles (no seam).
pub fn cylinder(r: f64, h: f64) -> Brep {
    extrude(
        &Profile::Circle {
            center: DVec2::ZERO,
            radius: r,
        },
        &[],
        h,
    )
}

/// As [`cylinder`], with a seam edge in the side face's single loop.
pub fn cylinder_with_seam(r: f64, h: f64) -> Brep {
    extrude_with_seams(
        &Profile::Circle {
            center: DVec2::ZERO,
            radius: r,
        },
        &[],
        h,
    )
}

/// A cone with its base circle (radius `r`) at z = 0 and apex at z = `h`;
/// the cone face has the base circle and a vertex loop at the apex, its
/// frame at the apex pointing down (semi-angle positive, as STEP requires).
pub fn cone(r: f64, h: f64) -> Brep {
    let mut b = Brep::new();
    let v0 = b.add_vertex(DVec3::new(r, 0.0, 0.0));
    let apex = b.add_vertex(DVec3::new(0.0, 0.0, h));
    let e = b.add_edge(Edge {
        start: v0,
        end: v0,
        curve: Curve::Circle {
            frame: Frame::WORLD,
            radius: r,
        },
        same_sense: true,
    });
    let side_outer = b.add_loop(lp(vec![ce(e, true)], true));
    let side_apex = b.add_loop(Loop {
        coedges: vec![],
        vertex: Some(apex),
        orientation: true,
        outer: false,
    });
    let side = b.add_face(Face {
        surface: Surface::Cone {
            frame: Frame::from_axis_ref(DVec3::new(0.0, 0.0, h), -DVec3::Z, Some(DVec3::X)),
            radius: 0.0,
            semi_angle: (r / h).atan(),
        },
        same_sense: true,
        loops: vec![side_outer, side_apex],
        name: "cone".into(),
    });
    let base_loop = b.add_loop(lp(vec![ce(e, false)], true));
    let base = b.add_face(Face {
        surface: Surface::Plane {
            frame: Frame::WORLD,
        },
        same_sense: false,
        loops: vec![base_loop],
        name: "base".into(),
    });
    let s = b.add_shell(Shell {
        faces: vec![base, side],
        closed: true,
    });
    b.add_solid(Solid {
        shells: vec![s],
        name: "cone".into(),
    });
    b
}

/// The upper half of a ball of radius `r` centred at the origin: a sphere
/// face bounded only by the equator (closed through the pole) and a disc.
pub fn hemisphere(r: f64) -> Brep {
    let mut b = Brep::new();
    let v0 = b.add_vertex(DVec3::new(r, 0.0, 0.0));
    let e = b.add_edge(Edge {
        start: v0,
        end: v0,
        curve: Curve::Circle {
            frame: Frame::WORLD,
            radius: r,
        },
        same_sense: true,
    });
    let l1 = b.add_loop(lp(vec![ce(e, true)], true));
    let dome = b.add_face(Face {
        surface: Surface::Sphere {
            frame: Frame::WORLD,
            radius: r,
        },
        same_sense: true,
        loops: vec![l1],
        name: "dome".into(),
    });
    let l2 = b.add_loop(lp(vec![ce(e, false)], true));
    let base = b.add_face(Face {
        surface: Surface::Plane {
            frame: Frame::WORLD,
        },
        same_sense: false,
        loops: vec![l2],
        name: "base".into(),
    });
    let s = b.add_shell(Shell {
        faces: vec![base, dome],
        closed: true,
    });
    b.add_solid(Solid {
        shells: vec![s],
        name: "hemisphere".into(),
    });
    b
}
