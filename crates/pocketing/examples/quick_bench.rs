//! The pocket bench without peers (FreeCAD, TOPP-RA), for quick before/after runs:
//! `cargo run --release -p thinplan-pocketing --example quick_bench [-- L/D ...]`.
use thinplan_pocketing::bench::{bench_pockets, format_table, BenchConfig};

fn main() {
    let lds: Vec<f64> = std::env::args()
        .skip(1)
        .filter_map(|a| a.parse().ok())
        .collect();
    let cfg = BenchConfig {
        adaptive: None,
        toppra: None,
        ..BenchConfig::cli()
    };
    let cfg = if lds.is_empty() {
        cfg
    } else {
        BenchConfig {
            l_over_d: lds,
            ..cfg
        }
    };
    let t0 = std::time::Instant::now();
    let rows = bench_pockets(&cfg).expect("bench");
    print!("{}", format_table(&rows));
    println!("({:.1} s)", t0.elapsed().as_secs_f64());
}
