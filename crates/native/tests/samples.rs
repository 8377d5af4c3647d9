//! Every sample part builds into a closed, manifold solid whose volume is
//! the sum of the prism volumes, computed here independently from the RON
//! profiles (shoelace + circular segments, closed-form for helpers).

use std::collections::{BTreeSet, HashMap};
use std::f64::consts::PI;
use std::path::{Path, PathBuf};

use thinplan_brep::Brep;
use thinplan_native::{load_labels, load_part, load_part_labels, Contour, PartSpec, Segment};

fn parts_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/parts")
}

fn sample_paths() -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(parts_dir())
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.to_string_lossy().ends_with(".part.ron"))
        .collect();
    v.sort();
    v
}

/// Independent closed-loop manifold check on a B-rep.
pub fn assert_closed_manifold(b: &Brep, what: &str) {
    let mut uses: HashMap<usize, (u32, u32)> = HashMap::new();
    for f in &b.faces {
        for &l in &f.loops {
            let cs = &b.loops[l].coedges;
            assert!(!cs.is_empty(), "{what}: empty loop in {}", f.name);
            for i in 0..cs.len() {
                let (c, n) = (cs[i], cs[(i + 1) % cs.len()]);
                assert_eq!(
                    b.coedge_end(c),
                    b.coedge_start(n),
                    "{what}: loop of face {} is not a chain",
                    f.name
                );
                let u = uses.entry(c.edge).or_default();
                if c.forward {
                    u.0 += 1
                } else {
                    u.1 += 1
                }
            }
        }
    }
    assert_eq!(uses.len(), b.edges.len(), "{what}: unused edges");
    for (e, u) in uses {
        assert_eq!(u, (1, 1), "{what}: edge {e} used {u:?}");
    }
    // Euler–Poincaré for one shell with inner loops: V − E + F − (L − F) = 2(1 − G).
    // We only check that the left side is even (a closed orientable surface).
    let loops: usize = b.faces.iter().map(|f| f.loops.len()).sum();
    let chi = b.vertices.len() as i64 - b.edges.len() as i64 + b.faces.len() as i64
        - (loops as i64 - b.faces.len() as i64);
    assert_eq!(
        chi.rem_euclid(2),
        0,
        "{what}: odd Euler characteristic {chi}"
    );
}

fn arc_segment_area(r: f64, sweep: f64) -> f64 {
    // Signed area between a chord and its arc.
    0.5 * r * r * (sweep - sweep.sin())
}

/// |area| of a contour, computed independently of the crate.
pub fn contour_area(c: &Contour) -> f64 {
    match c {
        Contour::Rect { min, max } => (max.0 - min.0) * (max.1 - min.1),
        Contour::RoundedRect { min, max, radius } => {
            (max.0 - min.0) * (max.1 - min.1) - (4.0 - PI) * radius * radius
        }
        Contour::Circle { radius, .. } => PI * radius * radius,
        Contour::Slot { from, to, width } => {
            let l = ((to.0 - from.0).powi(2) + (to.1 - from.1).powi(2)).sqrt();
            l * width + PI * (width / 2.0).powi(2)
        }
        Contour::Polygon { points, radius } => {
            let n = points.len();
            let mut a2 = 0.0;
            for i in 0..n {
                let (p, q) = (points[i], points[(i + 1) % n]);
                a2 += p.0 * q.1 - q.0 * p.1;
            }
            let s = a2.signum();
            let mut corr = 0.0;
            for i in 0..n {
                let (a, p, b) = (points[(i + n - 1) % n], points[i], points[(i + 1) % n]);
                let d1 = (p.0 - a.0, p.1 - a.1);
                let d2 = (b.0 - p.0, b.1 - p.1);
                let turn = (d1.0 * d2.1 - d1.1 * d2.0).atan2(d1.0 * d2.0 + d1.1 * d2.1);
                let cut = radius * radius * ((turn.abs() / 2.0).tan() - turn.abs() / 2.0);
                corr += if turn.signum() == s { cut } else { -cut };
            }
            (a2 / 2.0).abs() - corr
        }
        Contour::Path { start, segments } => {
            let mut a = 0.0;
            let mut cur = *start;
            for s in segments {
                let (to, seg) = match s {
                    Segment::Line { to, .. } => (*to, 0.0),
                    Segment::Arc {
                        to, centre, ccw, ..
                    } => {
                        let r = ((cur.0 - centre.0).powi(2) + (cur.1 - centre.1).powi(2)).sqrt();
                        let a0 = (cur.1 - centre.1).atan2(cur.0 - centre.0);
                        let a1 = (to.1 - centre.1).atan2(to.0 - centre.0);
                        let sweep = if *ccw {
                            (a1 - a0).rem_euclid(2.0 * PI)
                        } else {
                            -(a0 - a1).rem_euclid(2.0 * PI)
                        };
                        (*to, arc_segment_area(r, sweep))
                    }
                    Segment::Bulge { to, bulge, .. } => {
                        let sweep = 4.0 * bulge.atan();
                        let chord = ((to.0 - cur.0).powi(2) + (to.1 - cur.1).powi(2)).sqrt();
                        let r = chord / (2.0 * (sweep / 2.0).sin().abs());
                        (*to, arc_segment_area(r, sweep))
                    }
                };
                a += 0.5 * (cur.0 * to.1 - to.0 * cur.1) + seg;
                cur = to;
            }
            a.abs()
        }
        Contour::Repeat { count, of, .. } => *count as f64 * contour_area(of),
    }
}

pub fn independent_volume(spec: &PartSpec) -> f64 {
    spec.prisms
        .iter()
        .map(|p| {
            let area = contour_area(&p.profile.outer)
                - p.profile.holes.iter().map(contour_area).sum::<f64>();
            area * (p.extent.1 - p.extent.0)
        })
        .sum()
}

#[test]
fn at_least_eight_samples() {
    let names: BTreeSet<String> = sample_paths()
        .iter()
        .map(|p| p.file_name().unwrap().to_string_lossy().into_owned())
        .collect();
    for n in [
        "tall_rib",
        "flange_cutouts",
        "wall_holes",
        "flange_web_slot",
        "crossing_ribs",
        "isogrid",
        "pentagon_pocket",
        "wing_rib",
    ] {
        assert!(
            names.contains(&format!("{n}.part.ron")),
            "missing sample {n}"
        );
    }
}

#[test]
fn every_sample_builds_closed_manifold_with_exact_volume() {
    for path in sample_paths() {
        let what = path.display().to_string();
        let part = load_part(&path).unwrap_or_else(|e| panic!("{e}"));
        let brep = part.build().unwrap_or_else(|e| panic!("{e}"));
        assert_closed_manifold(&brep, &what);
        thinplan_native::check::check_solid(&brep).unwrap();
        let expected = independent_volume(part.spec());
        let v = thinplan_native::mass::volume(&brep);
        assert!(
            (v - expected).abs() <= 1e-6 * expected,
            "{what}: B-rep volume {v} vs profiles {expected}"
        );
        assert!((part.expected_volume() - expected).abs() <= 1e-9 * expected);
        // Solid structure.
        assert_eq!(brep.solids.len(), 1);
        assert_eq!(brep.shells.len(), 1);
        assert!(brep.shells[0].closed);
        assert_eq!(brep.shells[0].faces.len(), brep.faces.len());
        assert!(brep.faces.iter().all(|f| !f.name.is_empty()));
    }
}

#[test]
fn labels_load_and_name_existing_faces() {
    for path in sample_paths() {
        let part = load_part(&path).unwrap();
        let brep = part.build().unwrap();
        let names: BTreeSet<&str> = brep.faces.iter().map(|f| f.name.as_str()).collect();
        let labels = load_part_labels(&path)
            .unwrap()
            .unwrap_or_else(|| panic!("{}: no labels", path.display()));
        assert!(!labels.features.is_empty());
        assert_eq!(labels.part, part.name());
        for f in &labels.features {
            for face in &f.faces {
                assert!(
                    names.contains(face.as_str()),
                    "{}: label {} names missing face {face}",
                    path.display(),
                    f.id
                );
            }
        }
    }
    let l = load_labels(&parts_dir().join("wall_holes.labels.ron")).unwrap();
    assert_eq!(
        l.features
            .iter()
            .filter(|f| f.kind == thinplan_native::FeatureKind::Hole)
            .count(),
        4
    );
}

fn counts(name: &str) -> (usize, usize) {
    let part = load_part(&parts_dir().join(format!("{name}.part.ron"))).unwrap();
    let c = part.build().unwrap().face_kind_counts();
    assert_eq!(
        (c.cone, c.sphere, c.torus, c.bspline, c.other),
        (0, 0, 0, 0, 0)
    );
    (c.plane, c.cylinder)
}

#[test]
fn hand_counted_faces() {
    // tall_rib: base block 6 planes (its top keeps the rib footprint as an
    // inner loop); rib: 2 sides + 2 ends + top = 5 (its bottom is a contact
    // face and cancels). 11 planes.
    assert_eq!(counts("tall_rib"), (11, 0));
    // wall_holes: base 6 + wall 5 as above = 11 planes; 4 holes, one
    // cylinder each (two closed circle edges, no seam).
    assert_eq!(counts("wall_holes"), (11, 4));
    // pentagon_pocket: bottom; 4 sides (floor and wall-layer sides are
    // coplanar and merge); top with the pentagon inner loop; pocket floor;
    // 5 straight pocket walls = 12 planes; 5 corner cylinders.
    assert_eq!(counts("pentagon_pocket"), (12, 5));
    // flange_cutouts: web bottom, web top (flange footprint removed), the
    // y = 0 face (web edge + flange outer merge), the two L-shaped ends
    // (web end + flange end merge), web far edge, flange inner side = 7;
    // flange top: 4 pieces between the cut-outs; 2 straight sides per
    // cut-out = 6: 17 planes. One half-cylinder per cut-out bottom: 3.
    assert_eq!(counts("flange_cutouts"), (17, 3));
    // crossing_ribs: floor bottom + 4 sides + top outside the # + top of the
    // enclosed centre cell = 7; one merged top over all ribs = 1; x ribs:
    // each side cut in 3 by the crossing y-rib pieces: 2 ribs × 2 sides × 3
    // = 12, plus 4 ends; y ribs: 3 pieces × 2 sides × 2 ribs = 12, plus the 4
    // outer ends (inner ends are contact faces). 7 + 1 + 16 + 16 = 40.
    assert_eq!(counts("crossing_ribs"), (40, 0));
    // flange_web_slot: web bottom and top (each with the slot as inner
    // loop), 4 web edges with the y = 0 edge merged with the flange outer
    // face and the x ends L-shaped, 2 slot flats, flange inner side, flange
    // top = 10 planes; 2 half-cylinders at the slot ends.
    assert_eq!(counts("flange_web_slot"), (10, 2));
}

#[test]
fn true_cylinders_for_holes() {
    let part = load_part(&parts_dir().join("wall_holes.part.ron")).unwrap();
    let b = part.build().unwrap();
    let mut n = 0;
    for f in &b.faces {
        if let thinplan_brep::Surface::Cylinder { frame, radius } = &f.surface {
            n += 1;
            assert!((radius - 12.5).abs() < 1e-12);
            assert!(frame.z.y.abs() > 1.0 - 1e-12, "hole axis along y");
            assert!(!f.same_sense, "a hole's face points towards its axis");
            assert_eq!(f.loops.len(), 2);
            for &l in &f.loops {
                let cs = &b.loops[l].coedges;
                assert_eq!(cs.len(), 1);
                assert!(b.edges[cs[0].edge].is_closed());
            }
        }
    }
    assert_eq!(n, 4);
}
