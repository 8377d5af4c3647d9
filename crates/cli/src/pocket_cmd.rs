//! `thinplan bench pockets` and `thinplan pocket`: thin drivers of
//! `thinplan-pocketing`.

use std::path::Path;

use thinplan_pocketing::bench::{bench_pockets as run_bench, format_table, BenchConfig};
use thinplan_pocketing::timing::{time_path, MachineLimits};
use thinplan_pocketing::{curvilinear_path, pocket_svg, PocketProfile};

/// Prints the pocket benchmark table (or JSON rows with `json`): the `BenchConfig::cli()` set
/// (every bench pocket at L/D 0.5 to 100; FreeCAD Adaptive up to 10), with FreeCAD Adaptive
/// and TOPP-RA when their peers are installed.
pub fn bench_pockets(json: bool) -> Result<(), String> {
    let cfg = BenchConfig::cli();
    if cfg.adaptive.is_none() {
        eprintln!(
            "note: FreeCAD Adaptive peer not installed (run tools/peers/freecad/setup.sh): \
             `adaptive` is null"
        );
    }
    if cfg.toppra.is_none() {
        eprintln!(
            "note: TOPP-RA venv not found (run tools/peers/toppra/setup.sh): `toppra_ratio` is null"
        );
    }
    let t0 = std::time::Instant::now();
    let rows = run_bench(&cfg).map_err(|e| format!("bench pockets: {e}"))?;
    if json {
        println!(
            "{}",
            serde_json::to_string_pretty(&rows).map_err(|e| e.to_string())?
        );
    } else {
        println!(
            "D = V^2/(2A) = {:.1} mm (typical HSM: 500 mm/s, 5000 mm/s^2); tool = width/6, \
             stepover 0.4 D, finishing 0.1 D",
            cfg.limits.accel_distance()
        );
        print!("{}", format_table(&rows));
        println!("({:.1} s)", t0.elapsed().as_secs_f64());
    }
    Ok(())
}

/// Plans one pocket from a profile file (JSON, or RON for `.ron`; format in
/// `crates/pocketing/README.md`); writes the SVG and/or prints the path.
pub fn pocket(profile: &Path, svg: Option<&Path>, json: bool) -> Result<(), String> {
    let name = profile.display();
    let text = std::fs::read_to_string(profile).map_err(|e| format!("{name}: cannot read: {e}"))?;
    let is_ron = profile
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("ron"));
    let prof = PocketProfile::parse(&text, is_ron).map_err(|e| format!("{name}: {e}"))?;
    let (pocket, params) = prof.build().map_err(|e| format!("{name}: {e}"))?;
    let path = curvilinear_path(&pocket, &params).map_err(|e| format!("{name}: {e}"))?;
    let limits = MachineLimits::typical_hsm();
    let feed = limits.v_max[0].min(limits.v_max[1]);
    let sched = time_path(&path.points, feed, &limits);
    if let Some(out) = svg {
        std::fs::write(out, pocket_svg(&pocket, &path))
            .map_err(|e| format!("{}: cannot write SVG: {e}", out.display()))?;
    }
    if json {
        let points: Vec<[f64; 3]> = path
            .points
            .iter()
            .zip(&sched.v)
            .map(|(p, v)| [p.x, p.y, *v])
            .collect();
        let v = serde_json::json!({
            "pocket": pocket.name,
            "method": path.method.as_str(),
            "fallback_reason": path.fallback_reason,
            "tool_mm": params.tool_diameter,
            "stepover_mm": params.stepover,
            "finish_stepover_mm": params.finish_stepover,
            "length_mm": sched.length,
            "time_s": sched.total_time,
            "max_gap_mm": path.max_gap,
            "finish_start": path.finish_start,
            "points": points,
        });
        println!("{v}");
    } else {
        println!(
            "{}: {} path, {:.1} mm in {:.3} s (max gap {:.3} mm, stepover {:.3} mm, tool {:.3} mm)",
            pocket.name,
            path.method.as_str(),
            sched.length,
            sched.total_time,
            path.max_gap,
            params.stepover,
            params.tool_diameter
        );
        if let Some(r) = &path.fallback_reason {
            println!("fallback: {r}");
        }
        if let Some(out) = svg {
            println!("SVG written to {}", out.display());
        }
    }
    Ok(())
}
