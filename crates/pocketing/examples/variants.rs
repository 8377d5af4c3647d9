//! Savings experiments: the curvilinear path with different fields / distance blends vs the
//! offset baseline. `cargo run --release -p thinplan-pocketing --example variants [-- L/D ...]`
use thinplan_pocketing::bench::{bench_pockets, BenchConfig};
use thinplan_pocketing::Field;

fn main() {
    let lds: Vec<f64> = std::env::args()
        .skip(1)
        .filter_map(|a| a.parse().ok())
        .collect();
    let lds = if lds.is_empty() { vec![1.0, 10.0] } else { lds };
    let variants: Vec<(&str, Field, f64)> = vec![
        ("poisson", Field::Poisson, 0.0),
        ("eigen", Field::Eigen, 0.0),
        ("poisson+d 0.5", Field::Poisson, 0.5),
        ("poisson+d 0.8", Field::Poisson, 0.8),
        ("distance", Field::Poisson, 1.0),
    ];
    for (name, field, blend) in variants {
        let cfg = BenchConfig {
            l_over_d: lds.clone(),
            adaptive: None,
            toppra: None,
            field,
            distance_blend: blend,
            ..BenchConfig::default()
        };
        let t0 = std::time::Instant::now();
        let rows = bench_pockets(&cfg).expect("bench");
        for r in &rows {
            println!(
                "{name:<14} {:<17} L/D {:>5.1}: off {:>7.0} mm {:>6.2} s | curv {:>7.0} mm {:>6.2} s {:<15} gap {:.3}/{:.3} | save {:>6.1} %",
                r.pocket, r.l_over_d, r.offset.length_mm, r.offset.time_s,
                r.curvilinear.length_mm, r.curvilinear.time_s, r.curvilinear.method,
                r.curvilinear.max_gap_mm, r.stepover_mm, r.saving_pct
            );
        }
        println!("  ({:.1} s)", t0.elapsed().as_secs_f64());
    }
}
