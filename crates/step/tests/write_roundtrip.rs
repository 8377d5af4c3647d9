//! `write_step` → `read_step_bytes` gives the same B-rep: for every native
//! sample part, a real STEP file and a solid with a void.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use serde_json::Value;
use thinplan_brep::{Brep, Solid};
use thinplan_step::{read_step_bytes, write_step, Limits};

fn parts_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/parts")
}

fn sample_parts() -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(parts_dir())
        .expect("assets/parts")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| {
            p.file_name()
                .and_then(|n| n.to_str())
                .is_some_and(|n| n.ends_with(".part.ron"))
        })
        .collect();
    v.sort();
    v
}

fn read_back(text: &str) -> Brep {
    let m = read_step_bytes(text.as_bytes(), &Limits::default()).expect("written STEP reads");
    assert_eq!(m.units, "mm");
    assert!(m.warnings.is_empty(), "warnings: {:?}", m.warnings);
    assert!(m.schema.starts_with("AUTOMOTIVE_DESIGN"), "{}", m.schema);
    m.brep
}

/// Checks that `b` (read back) is `a` (written): counts, face kinds, names
/// and senses in order, and a consistent one-to-one map of edges and
/// vertices through the loops (the reader numbers vertices and edges in the
/// order the topology first uses them) with equal coordinates. Void shells
/// come back as written: `ORIENTED_CLOSED_SHELL(.F.)` turns its faces' bounds
/// over with their normals.
fn assert_same(a: &Brep, b: &Brep, what: &str) {
    assert_eq!(a.solids.len(), b.solids.len(), "{what}: solids");
    assert_eq!(a.shells.len(), b.shells.len(), "{what}: shells");
    assert_eq!(a.faces.len(), b.faces.len(), "{what}: faces");
    assert_eq!(a.loops.len(), b.loops.len(), "{what}: loops");
    assert_eq!(a.edges.len(), b.edges.len(), "{what}: edges");
    assert_eq!(a.vertices.len(), b.vertices.len(), "{what}: vertices");
    for (sa, sb) in a.solids.iter().zip(&b.solids) {
        assert_eq!(sa.name, sb.name, "{what}: solid name");
        assert_eq!(
            sa.shells.len(),
            sb.shells.len(),
            "{what}: shells of a solid"
        );
    }
    let mut edge_map: HashMap<usize, usize> = HashMap::new();
    let mut vert_map: HashMap<usize, usize> = HashMap::new();
    let mut map_vertex = |va: usize, vb: usize, at: &str| {
        let prev = *vert_map.entry(va).or_insert(vb);
        assert_eq!(prev, vb, "{what}: {at}: vertex {va} maps to two vertices");
        let (pa, pb) = (a.vertices[va].point, b.vertices[vb].point);
        assert!(
            (pa - pb).abs().max_element() <= 1e-9,
            "{what}: {at}: vertex {pa} read back as {pb}"
        );
    };
    for (fi, (fa, fb)) in a.faces.iter().zip(&b.faces).enumerate() {
        let at = format!("face {fi} '{}'", fa.name);
        assert_eq!(fa.name, fb.name, "{what}: {at}: name");
        assert_eq!(
            fa.surface.kind_name(),
            fb.surface.kind_name(),
            "{what}: {at}: kind"
        );
        assert_eq!(fa.same_sense, fb.same_sense, "{what}: {at}: same_sense");
        assert_close(&fa.surface, &fb.surface, &format!("{what}: {at}: surface"));
        assert_eq!(fa.loops.len(), fb.loops.len(), "{what}: {at}: loops");
        for (&la, &lb) in fa.loops.iter().zip(&fb.loops) {
            let (la, lb) = (&a.loops[la], &b.loops[lb]);
            assert_eq!(la.outer, lb.outer, "{what}: {at}: outer");
            assert_eq!(
                la.orientation, lb.orientation,
                "{what}: {at}: bound orientation"
            );
            assert_eq!(la.coedges.len(), lb.coedges.len(), "{what}: {at}: coedges");
            if let (Some(va), Some(vb)) = (la.vertex, lb.vertex) {
                map_vertex(va, vb, &at);
            }
            assert_eq!(la.vertex.is_some(), lb.vertex.is_some(), "{what}: {at}");
            for (ca, cb) in la.coedges.iter().zip(&lb.coedges) {
                assert_eq!(ca.forward, cb.forward, "{what}: {at}: coedge sense");
                let prev = *edge_map.entry(ca.edge).or_insert(cb.edge);
                assert_eq!(prev, cb.edge, "{what}: {at}: edge {} maps twice", ca.edge);
                let (ea, eb) = (&a.edges[ca.edge], &b.edges[cb.edge]);
                assert_eq!(ea.same_sense, eb.same_sense, "{what}: {at}: edge sense");
                assert_close(&ea.curve, &eb.curve, &format!("{what}: {at}: curve"));
                map_vertex(ea.start, eb.start, &at);
                map_vertex(ea.end, eb.end, &at);
            }
        }
    }
    // One-to-one.
    let mut targets: Vec<usize> = vert_map.values().copied().collect();
    targets.sort_unstable();
    targets.dedup();
    assert_eq!(
        targets.len(),
        vert_map.len(),
        "{what}: vertex map not injective"
    );
    let mut targets: Vec<usize> = edge_map.values().copied().collect();
    targets.sort_unstable();
    targets.dedup();
    assert_eq!(
        targets.len(),
        edge_map.len(),
        "{what}: edge map not injective"
    );

    let (va, vb) = (a.volume(), b.volume());
    assert!(
        (va - vb).abs() <= 1e-6 * va.abs(),
        "{what}: volume {va} read back as {vb}"
    );
}

/// The same value up to rounding: serialised to JSON, numbers within 1e-9
/// (mm, radians, unit-vector components), everything else equal.
fn assert_close<T: serde::Serialize>(a: &T, b: &T, what: &str) {
    fn walk(a: &Value, b: &Value, path: &mut String) -> Result<(), String> {
        match (a, b) {
            (Value::Number(x), Value::Number(y)) => {
                let (x, y) = (
                    x.as_f64().unwrap_or(f64::NAN),
                    y.as_f64().unwrap_or(f64::NAN),
                );
                if (x - y).abs() <= 1e-9 * x.abs().max(1.0) {
                    Ok(())
                } else {
                    Err(format!("{path}: {x} read back as {y}"))
                }
            }
            (Value::Array(x), Value::Array(y)) if x.len() == y.len() => {
                for (i, (p, q)) in x.iter().zip(y).enumerate() {
                    let n = path.len();
                    path.push_str(&format!("[{i}]"));
                    walk(p, q, path)?;
                    path.truncate(n);
                }
                Ok(())
            }
            (Value::Object(x), Value::Object(y)) if x.len() == y.len() => {
                for (k, p) in x {
                    let q = y.get(k).ok_or_else(|| format!("{path}.{k} missing"))?;
                    let n = path.len();
                    path.push_str(&format!(".{k}"));
                    walk(p, q, path)?;
                    path.truncate(n);
                }
                Ok(())
            }
            _ if a == b => Ok(()),
            _ => Err(format!("{path}: {a} read back as {b}")),
        }
    }
    let (a, b) = (
        serde_json::to_value(a).expect("serialises"),
        serde_json::to_value(b).expect("serialises"),
    );
    if let Err(e) = walk(&a, &b, &mut String::new()) {
        panic!("{what}: {e}");
    }
}

/// Writes, reads back, compares; checks determinism and that a second
/// generation keeps everything. Returns (faces, volume).
fn round_trip(brep: &Brep, name: &str) -> (usize, f64) {
    let text = write_step(brep, name);
    assert_eq!(text, write_step(brep, name), "{name}: not deterministic");
    let back = read_back(&text);
    assert_same(brep, &back, name);
    // A second generation (the read-back B-rep written and read again)
    // keeps everything too.
    let back2 = read_back(&write_step(&back, name));
    assert_same(&back, &back2, &format!("{name} (2nd generation)"));
    (brep.faces.len(), brep.volume())
}

#[test]
fn native_samples_round_trip() {
    let parts = sample_parts();
    assert!(parts.len() >= 8, "sample parts: {parts:?}");
    for path in parts {
        let part = thinplan_native::load_part(&path).expect("sample loads");
        let brep = part.build().expect("sample builds");
        let (faces, volume) = round_trip(&brep, part.name());
        // The exact volume of what was read back, against the analytic one.
        let back = read_back(&write_step(&brep, part.name()));
        let exact = thinplan_native::mass::volume(&back);
        let expected = part.expected_volume();
        let rel = (exact - expected).abs() / expected;
        assert!(
            rel <= 1e-6,
            "{}: exact volume {exact} vs {expected}",
            part.name()
        );
        eprintln!(
            "{}: {faces} faces, {} edges, {} vertices; volume {volume:.3} (tessellated), \
             {exact:.6} exact read back, expected {expected:.6} (rel. {rel:.1e})",
            part.name(),
            brep.edges.len(),
            brep.vertices.len()
        );
    }
}

#[test]
fn real_file_round_trips() {
    let Some(dir) = thinplan_testdata::data_dir("aagnet") else {
        return;
    };
    let m = thinplan_step::read_step_file(&dir.join("partC.step")).expect("partC reads");
    let (faces, volume) = round_trip(&m.brep, "partC");
    eprintln!("partC: {faces} faces, volume {volume:.6}");
}

/// A 100 mm cube with a 10 mm cubic void in its middle.
fn box_with_void() -> Brep {
    let cube = |name: &str, min: f64, max: f64| {
        let text = format!(
            "Part(name: \"{name}\", prisms: [Prism(id: \"b\", extent: ({min:?}, {max:?}), \
             profile: (outer: Rect(min: ({min:?}, {min:?}), max: ({max:?}, {max:?}))))])"
        );
        thinplan_native::parse_part(&text, name)
            .expect("cube parses")
            .build()
            .expect("cube builds")
    };
    let mut b = cube("outer", 0.0, 100.0);
    let inner = cube("void", 45.0, 55.0);
    let l0 = b.loops.len();
    b.append(&inner);
    // Reverse the inner cube's faces so that they point into the void.
    for lp in &mut b.loops[l0..] {
        lp.coedges.reverse();
        for c in &mut lp.coedges {
            c.forward = !c.forward;
        }
    }
    let inner_solid = b.solids.pop().expect("two solids");
    for &s in &inner_solid.shells {
        for &f in &b.shells[s].faces.clone() {
            b.faces[f].same_sense = !b.faces[f].same_sense;
        }
    }
    let outer = &mut b.solids[0];
    *outer = Solid {
        shells: [outer.shells.clone(), inner_solid.shells].concat(),
        name: "box_with_void".into(),
    };
    b
}

#[test]
fn solid_with_void_round_trips() {
    let b = box_with_void();
    let v = b.volume();
    assert!((v - 999_000.0).abs() < 1e-6 * 999_000.0, "volume {v}");
    let text = write_step(&b, "box_with_void");
    assert!(text.contains("BREP_WITH_VOIDS('box_with_void'"));
    assert!(text.contains("ORIENTED_CLOSED_SHELL('',*,"));
    round_trip(&b, "box_with_void");
}

#[test]
fn header_and_entities() {
    let part = thinplan_native::load_part(&parts_dir().join("wall_holes.part.ron")).unwrap();
    let text = write_step(&part.build().unwrap(), "wall 'holes'");
    for needle in [
        "ISO-10303-21;",
        "FILE_SCHEMA(('AUTOMOTIVE_DESIGN { 1 0 10303 214 1 1 1 1 }'));",
        "FILE_NAME('wall ''holes''','2000-01-01T00:00:00'",
        "SI_UNIT(.MILLI.,.METRE.)",
        "SI_UNIT($,.RADIAN.)",
        "UNCERTAINTY_MEASURE_WITH_UNIT(LENGTH_MEASURE(1.E-6)",
        "ADVANCED_BREP_SHAPE_REPRESENTATION('wall ''holes''',(#",
        "MANIFOLD_SOLID_BREP('wall_holes',#",
        "CYLINDRICAL_SURFACE('',#",
        "CIRCLE('',#",
        "FACE_OUTER_BOUND('',#",
        "FACE_BOUND('',#",
        "END-ISO-10303-21;",
    ] {
        assert!(text.contains(needle), "missing {needle}");
    }
    // Every real has a decimal point: no bare integers where reals go.
    assert!(!text.contains("CARTESIAN_POINT('',(0,"));
}
