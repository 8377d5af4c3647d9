//! Engagement of our paths and FreeCAD Adaptive's over a reduced bench sweep, as a Markdown
//! table: `cargo run --release -p thinplan-pocketing --example engagement_sweep -- [L/D ...]`
//! (default 1 4 10; TOPP-RA off). Our spiral is measured three ways: entered by stage 7's
//! helix (the planner's entry, `bench::HelixEntryRule`), by a plunge at its first point, and by
//! a helix about its centre with the spiral started where it leaves the helix circle
//! (`PocketPath::after_centred_helix`: its own length and time). With `--cost`: the measure's
//! run time per path beside the path generation and the feed schedule, at the first L/D.
use std::time::Instant;

use thinplan_pocketing::bench::{bench_family, bench_params, bench_pockets, BenchConfig};
use thinplan_pocketing::engagement::{
    engagement_profile, engagement_stats, EngagementParams, Entry,
};
use thinplan_pocketing::timing::{time_path, MachineLimits};
use thinplan_pocketing::{
    curvilinear_path, offset_path, Pocket, PocketError, PocketParams, PocketPath,
};

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let mut lds: Vec<f64> = args.iter().filter_map(|a| a.parse().ok()).collect();
    if lds.is_empty() {
        lds = vec![1.0, 4.0, 10.0];
    }
    if args.iter().any(|a| a == "--cost") {
        cost(lds[0]);
        return;
    }
    let cfg = BenchConfig {
        l_over_d: lds,
        toppra: None,
        adaptive_max_l_over_d: 10.0,
        compare_entries: true,
        ..BenchConfig::default()
    };
    match &cfg.helix_entry {
        Some(h) => eprintln!("helix entry {} D from {}", h.radius, h.source),
        None => eprintln!("note: no helix entry in the knowledge: our spiral plunges"),
    }
    if cfg.adaptive.is_none() {
        eprintln!("note: FreeCAD Adaptive peer not installed: its columns are `-`");
    }
    let t0 = Instant::now();
    let rows = bench_pockets(&cfg).expect("bench");
    let f = |x: Option<f64>, p: usize| x.map_or("-".to_string(), |x| format!("{x:.p$}"));
    println!(
        "| pocket | L/D | tool mm | path | length mm | time s | max° | p99° | max a_e/D |\n\
         | --- | --- | --- | --- | --- | --- | --- | --- | --- |"
    );
    for r in &rows {
        let d = r.tool_mm;
        let c = &r.curvilinear;
        let mut lines = vec![(
            format!(
                "ours ({}, {})",
                c.method,
                c.entry.as_deref().unwrap_or("plunge")
            ),
            Some(c.length_mm),
            Some(c.time_s),
            c.max_engagement_deg,
            c.p99_engagement_deg,
            c.max_radial_mm,
        )];
        if let Some(p) = &c.centred_helix {
            lines.push((
                format!(
                    "ours ({}, {}, started outside it)",
                    c.method,
                    p.entry.as_deref().unwrap_or("?")
                ),
                Some(p.length_mm),
                Some(p.time_s),
                p.max_engagement_deg,
                p.p99_engagement_deg,
                p.max_radial_mm,
            ));
        }
        if let Some(p) = &c.plunge {
            lines.push((
                format!("ours ({}, plunge)", c.method),
                Some(c.length_mm),
                Some(c.time_s),
                Some(p.max_engagement_deg),
                Some(p.p99_engagement_deg),
                Some(p.max_radial_mm),
            ));
        }
        for (name, p) in [
            ("offset", Some(&r.offset)),
            ("gap-matched offset", Some(&r.offset_gap_matched)),
            ("FreeCAD Adaptive", r.adaptive.as_ref()),
        ] {
            lines.push(match p {
                Some(p) => (
                    name.to_string(),
                    Some(p.length_mm),
                    Some(p.time_s),
                    p.max_engagement_deg,
                    p.p99_engagement_deg,
                    p.max_radial_mm,
                ),
                None => (name.to_string(), None, None, None, None, None),
            });
        }
        for (k, (name, len, t, mx, p99, rad)) in lines.into_iter().enumerate() {
            let (pk, ld, tool) = if k == 0 {
                (
                    r.pocket.clone(),
                    format!("{}", r.l_over_d),
                    format!("{d:.2}"),
                )
            } else {
                (String::new(), String::new(), String::new())
            };
            println!(
                "| {pk} | {ld} | {tool} | {name} | {} | {} | {} | {} | {} |",
                f(len, 0),
                f(t, 2),
                f(mx, 0),
                f(p99, 0),
                f(rad.map(|x| x / d), 2)
            );
        }
    }
    eprintln!("({:.1} s)", t0.elapsed().as_secs_f64());
}

/// Run times (ms) per bench pocket at one L/D: path generation, feed schedule, engagement.
fn cost(ld: f64) {
    let limits = MachineLimits::typical_hsm();
    let l = ld * limits.accel_distance();
    let ep = EngagementParams::default();
    println!("L/D {ld}: ms per path (generation / feed schedule / engagement), positions");
    for bp in bench_family(l) {
        let params = bench_params(&bp);
        type Make = fn(&Pocket, &PocketParams) -> Result<PocketPath, PocketError>;
        fn zigzag(p: &Pocket, q: &PocketParams) -> Result<PocketPath, PocketError> {
            thinplan_pocketing::zigzag_path(p, q, 0.0)
        }
        let makers: [(&str, Make); 3] = [
            ("offset", offset_path),
            ("curvilinear", curvilinear_path),
            ("zigzag 0°", zigzag),
        ];
        for (name, make) in makers {
            let t0 = Instant::now();
            let path = make(&bp.pocket, &params).expect("path");
            let t1 = Instant::now();
            let sched = time_path(&path.points, 500.0, &limits);
            let t2 = Instant::now();
            let e = engagement_stats(&path.points, params.tool_diameter, Entry::Plunge, &ep);
            let t3 = Instant::now();
            // how much of the path cuts like a slot (≥ 150°), and how far along it ends
            let prof = engagement_profile(&path.points, params.tool_diameter, Entry::Plunge, &ep);
            let total = prof.last().map_or(1.0, |e| e.s);
            let slotting: Vec<f64> = prof
                .iter()
                .filter(|e| e.angle_deg >= 150.0)
                .map(|e| e.s)
                .collect();
            let share = slotting.len() as f64 / prof.len().max(1) as f64;
            let last = slotting.last().map_or(0.0, |s| s / total);
            let ms = |a: Instant, b: Instant| (b - a).as_secs_f64() * 1e3;
            println!(
                "{:<17} {:<12} {:>8.1} {:>8.1} {:>8.1}  ({:.0} mm = {:.0} D, max {:.0}° at {:.3} of the length, p99 {:.0}°; ≥ 150° on {:.1} % of it, the last at {:.3})",
                bp.pocket.name,
                name,
                ms(t0, t1),
                ms(t1, t2),
                ms(t2, t3),
                sched.length,
                sched.length / params.tool_diameter,
                e.map_or(f64::NAN, |e| e.max_engagement_deg),
                e.map_or(f64::NAN, |e| e.max_at_fraction),
                e.map_or(f64::NAN, |e| e.p99_engagement_deg),
                100.0 * share,
                last
            );
        }
    }
}
