//! Recognition time against face count on generated parts.
//!
//! One cell is a native RON part: a 60 × 60 × 2 web tile with two ribs along
//! x crossed by a rib along y (split into pieces, as native parts need), a
//! round hole in the web and a rib standing on a flange-like edge wall. The
//! cell is replicated on a square grid (`Brep::append` + translation) until
//! the part has the wanted number of faces; all cells share their planes,
//! which is the worst case for plane bucketing. Prints `faces | ms`.
//!
//! `cargo run --release -p thinplan-recognise --example recognise_bench [-- 1000 5000 …]`

use glam::{DMat4, DVec3};

const CELL: &str = r#"Part(name: "cell", prisms: [
  Prism(id: "web", extent: (0.0, 2.0),
        profile: (outer: Rect(min: (0.0, 0.0), max: (60.0, 60.0)),
                  holes: [Circle(centre: (45.0, 45.0), radius: 6.0)])),
  Prism(id: "rx1", frame: (origin: (0.0, 20.0, 0.0), x_dir: (1.0, 0.0, 0.0), y_dir: (0.0, 0.0, 1.0)),
        extent: (-1.0, 1.0), profile: (outer: Rect(min: (5.0, 2.0), max: (55.0, 20.0)))),
  Prism(id: "rx2", frame: (origin: (0.0, 32.0, 0.0), x_dir: (1.0, 0.0, 0.0), y_dir: (0.0, 0.0, 1.0)),
        extent: (-1.0, 1.0), profile: (outer: Rect(min: (5.0, 2.0), max: (55.0, 20.0)))),
  Prism(id: "rya", frame: (origin: (30.0, 0.0, 0.0), x_dir: (0.0, 1.0, 0.0), y_dir: (0.0, 0.0, 1.0)),
        extent: (-1.0, 1.0), profile: (outer: Rect(min: (5.0, 2.0), max: (19.0, 20.0)))),
  Prism(id: "ryb", frame: (origin: (30.0, 0.0, 0.0), x_dir: (0.0, 1.0, 0.0), y_dir: (0.0, 0.0, 1.0)),
        extent: (-1.0, 1.0), profile: (outer: Rect(min: (21.0, 2.0), max: (31.0, 20.0)))),
  Prism(id: "ryc", frame: (origin: (30.0, 0.0, 0.0), x_dir: (0.0, 1.0, 0.0), y_dir: (0.0, 0.0, 1.0)),
        extent: (-1.0, 1.0), profile: (outer: Rect(min: (33.0, 2.0), max: (40.0, 20.0)))),
])"#;

fn main() {
    let targets: Vec<usize> = {
        let a: Vec<usize> = std::env::args()
            .skip(1)
            .filter_map(|s| s.parse().ok())
            .collect();
        if a.is_empty() {
            vec![1_000, 2_000, 5_000, 10_000, 20_000, 50_000]
        } else {
            a
        }
    };
    let cell = thinplan_native::parse_part(CELL, "cell")
        .unwrap()
        .build()
        .unwrap();
    let k = thinplan_knowledge::Knowledge::builtin().unwrap();
    let m = k.machines["hsm_5axis"].clone();
    let single = thinplan_recognise::recognise(&cell, DVec3::Z, &k, &m);
    let walls = single
        .features
        .iter()
        .filter(|f| f.kind == thinplan_plan::StiffnessKind::Wall)
        .count();
    println!("cell: {} faces, {walls} walls", cell.faces.len());
    println!(
        "{:>8} | {:>6} | {:>9} | {:>8} | {:>10}",
        "faces", "cells", "features", "ms", "µs/face"
    );
    println!(
        "{:->8}-|-{:->6}-|-{:->9}-|-{:->8}-|-{:->10}",
        "", "", "", "", ""
    );
    for target in targets {
        let cells = target.div_ceil(cell.faces.len()).max(1);
        let side = (cells as f64).sqrt().ceil() as usize;
        let mut brep = thinplan_brep::Brep::new();
        for i in 0..cells {
            let mut c = cell.clone();
            let (gx, gy) = ((i % side) as f64, (i / side) as f64);
            c.transform(&DMat4::from_translation(DVec3::new(
                gx * 70.0,
                gy * 70.0,
                0.0,
            )));
            brep.append(&c);
        }
        let t = std::time::Instant::now();
        let r = thinplan_recognise::recognise(&brep, DVec3::Z, &k, &m);
        let ms = t.elapsed().as_secs_f64() * 1e3;
        let got = r
            .features
            .iter()
            .filter(|f| f.kind == thinplan_plan::StiffnessKind::Wall)
            .count();
        assert_eq!(got, walls * cells, "every cell recognised the same");
        // Phases: adjacency, walls, depressions, connections among walls.
        let t0 = std::time::Instant::now();
        let adj = thinplan_brep::edge_adjacency(&brep);
        let t_adj = t0.elapsed().as_secs_f64() * 1e3;
        let t1 = std::time::Instant::now();
        let mut w = Vec::new();
        let ws = thinplan_recognise::walls::find_walls(
            &brep,
            &adj,
            DVec3::Z,
            &k.wall_recognition,
            &mut w,
        );
        let t_walls = t1.elapsed().as_secs_f64() * 1e3;
        let t2 = std::time::Instant::now();
        let _ =
            thinplan_recognise::connect::connect(&brep, &adj, DVec3::Z, &ws, &k.wall_recognition);
        let t_conn = t2.elapsed().as_secs_f64() * 1e3;
        let t3 = std::time::Instant::now();
        let _ = thinplan_recognise::depressions::find_depressions(
            &brep,
            &adj,
            DVec3::Z,
            &k.depression_recognition,
            &ws,
            &mut w,
        );
        let t_dep = t3.elapsed().as_secs_f64() * 1e3;
        println!(
            "{:>8} | {:>6} | {:>9} | {:>8.1} | {:>10.1} | adjacency {:.1} walls {:.1} depressions {:.1} connect(walls) {:.1}",
            brep.faces.len(),
            cells,
            r.features.len(),
            ms,
            ms * 1e3 / brep.faces.len() as f64,
            t_adj,
            t_walls,
            t_dep,
            t_conn
        );
    }
}
