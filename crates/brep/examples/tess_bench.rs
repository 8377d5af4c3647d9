//! Rough timings of tessellation and mass properties on the test shapes:
//! `cargo run --release -p thinplan-brep --features test-shapes --example tess_bench`.

use std::time::Instant;

use glam::DVec2;
use thinplan_brep::test_shapes::*;
use thinplan_brep::{tessellate, tessellate_face, TessTolerance};

fn main() {
    let holes: Vec<(DVec2, f64)> = (0..5)
        .flat_map(|i| {
            (0..5).map(move |j| {
                (
                    DVec2::new(10.0 + 20.0 * i as f64, 10.0 + 20.0 * j as f64),
                    4.0,
                )
            })
        })
        .collect();
    let shapes = [
        ("box", box_shape(10.0, 20.0, 30.0)),
        (
            "box_with_hole",
            box_with_hole(10.0, 20.0, 30.0, DVec2::new(5.0, 8.0), 3.0),
        ),
        (
            "plate_25_holes",
            plate_with_holes(100.0, 100.0, 5.0, &holes),
        ),
        ("cylinder", cylinder(20.0, 50.0)),
        ("cone", cone(10.0, 20.0)),
        ("hemisphere", hemisphere(10.0)),
    ];
    if std::env::args().any(|a| a == "--hot") {
        let b = &shapes[1].1;
        for _ in 0..3000 {
            let _ = tessellate_face(b, 5, &TessTolerance::default()).unwrap();
        }
        return;
    }
    for (name, b) in &shapes {
        if std::env::args().any(|a| a == "--faces") {
            for f in 0..b.faces.len() {
                let t = Instant::now();
                let mut m = tessellate_face(b, f, &TessTolerance::default()).unwrap();
                for _ in 0..99 {
                    m = tessellate_face(b, f, &TessTolerance::default()).unwrap();
                }
                println!(
                    "  {name} face {f} {} {} tris {:?}",
                    b.faces[f].surface.kind_name(),
                    m.triangles.len(),
                    t.elapsed() / 100
                );
            }
        }
        let t = Instant::now();
        let m = tessellate(b, &TessTolerance::default());
        let dt = t.elapsed();
        let t = Instant::now();
        let mp = b.mass_properties();
        let dm = t.elapsed();
        let nm = tessellate(b, &mp.tolerance).triangles.len();
        println!(
            "{name:16} default: {:6} tris {:8.2?} | mass (chord {:.1e}, {} tris): vol {:.3} area {:.3} {:8.2?}",
            m.triangles.len(),
            dt,
            mp.tolerance.chord,
            nm,
            mp.volume,
            mp.area,
            dm
        );
    }
}
