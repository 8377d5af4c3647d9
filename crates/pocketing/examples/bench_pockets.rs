//! Print the pocketing benchmark: `cargo run --release -p thinplan-pocketing --example bench_pockets [-- --json]`.
use thinplan_pocketing::bench::{bench_pockets, format_table, BenchConfig};

fn main() {
    let json = std::env::args().any(|a| a == "--json");
    let cfg = BenchConfig::default();
    let d = cfg.limits.accel_distance();
    let t0 = std::time::Instant::now();
    let rows = bench_pockets(&cfg).expect("bench");
    if json {
        println!("{}", serde_json::to_string_pretty(&rows).unwrap());
    } else {
        println!(
            "D = V²/(2A) = {d:.1} mm; FreeCAD Adaptive: {}",
            if cfg.adaptive.is_some() {
                "yes"
            } else {
                "not set up (tools/peers/freecad/setup.sh)"
            }
        );
        print!("{}", format_table(&rows));
        println!("({:.1} s)", t0.elapsed().as_secs_f64());
    }
}
