//! Stages 2–6 on generated rib fields of growing size: `cargo bench -p
//! thinplan-pipeline --bench stages`. Prints seconds per stage and the
//! growth ratio per doubling (n·log n would be ≈ 2.2).

use std::time::Instant;

use thinplan_pipeline::{load_knowledge, make_setup, Session, SetupRequest};
use thinplan_plan::Stage;

/// `walls` thin ribs in rows of 50 on one web, 30 mm apart (room for B_RF
/// on both sides), 80 mm long, 1.5 mm thick, 40 mm tall.
fn rib_field(walls: usize) -> String {
    let per_row = 50.min(walls);
    let rows = walls.div_ceil(per_row);
    let (pitch, row_pitch) = (30.0, 110.0);
    let (w, d) = (
        per_row as f64 * pitch + 20.0,
        rows as f64 * row_pitch + 20.0,
    );
    let mut s = format!(
        "Part(name: \"rib_field_{walls}\", description: \"{walls} ribs on a web\", prisms: [\n\
         Prism(id: \"web\", extent: (0.0, 3.0), profile: (outer: Rect(min: (0.0, 0.0), max: ({w}, {d})))),\n"
    );
    for i in 0..walls {
        let (r, c) = (i / per_row, i % per_row);
        let x = 25.0 + c as f64 * pitch;
        let y0 = 25.0 + r as f64 * row_pitch;
        s += &format!(
            "Prism(id: \"rib{i}\", frame: (origin: ({x}, 0.0, 0.0), x_dir: (0.0, 1.0, 0.0), y_dir: (0.0, 0.0, 1.0)), \
             extent: (-0.75, 0.75), profile: (outer: Rect(min: ({y0}, 3.0), max: ({}, 43.0)))),\n",
            y0 + 80.0
        );
    }
    s + "])\n"
}

fn main() {
    let dir = std::env::temp_dir().join(format!("thinplan-bench-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    println!("| walls | recognise+connect s | sequence s | determine s | resolve s | stages 2–6 s | machining features |");
    println!("|---:|---:|---:|---:|---:|---:|---:|");
    let mut last: Option<f64> = None;
    for walls in [25, 50, 100, 200] {
        let path = dir.join(format!("rib_field_{walls}.part.ron"));
        std::fs::write(&path, rib_field(walls)).expect("write part");
        let k = load_knowledge(None).expect("knowledge");
        let setup = make_setup(&SetupRequest::default(), &k).expect("set-up");
        let mut s = Session::open(path.to_str().expect("utf-8"), setup, k).expect("opens");
        let mut times = Vec::new();
        for stage in [
            Stage::Recognise,
            Stage::Sequence,
            Stage::Determine,
            Stage::Resolve,
        ] {
            let t = Instant::now();
            s.run_stage(stage).expect("stage runs");
            times.push(t.elapsed().as_secs_f64());
        }
        let total: f64 = times.iter().sum();
        println!(
            "| {walls} | {:.3} | {:.3} | {:.3} | {:.3} | {total:.3} | {} |",
            times[0],
            times[1],
            times[2],
            times[3],
            s.plan.machining_features.len()
        );
        if let Some(prev) = last {
            eprintln!("  growth per doubling: {:.2}", total / prev);
        }
        last = Some(total);
    }
    let _ = std::fs::remove_dir_all(&dir);
}
