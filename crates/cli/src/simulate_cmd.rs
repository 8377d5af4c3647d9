//! `thinplan simulate PART PROGRAM`: a thin driver of `thinplan-stocksim`,
//! the independent Z-map stock simulation (it reads the G-code text itself).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use thinplan_stocksim::{
    parse_bytes, parse_tool_table, simulate, Blank, DefectSummary, SimConfig, StockReport,
};

/// Replay an NC program on a Z-map of the blank and compare the stock with
/// the part: gouges, leftover (missed / unreachable), rapids into stock,
/// air cutting.
#[derive(clap::Args, Debug, Clone)]
pub struct SimulateArgs {
    /// The part: a STEP or native file, or builtin:NAME.
    pub part: String,
    /// The NC program (RS274NGC / Fanuc G-code as thinplan's posts write it).
    pub program: PathBuf,
    /// LinuxCNC tool table (`T1 P1 D12 ;em12 r0.5`: `r` = corner radius,
    /// `ball` = ball end mill). Default: `tool.tbl` next to the program.
    #[arg(long)]
    pub tool_table: Option<PathBuf>,
    /// The box blank "xmin,ymin,zmin,xmax,ymax,zmax" in mm (default: the
    /// part's bounding box).
    #[arg(long, allow_hyphen_values = true)]
    pub blank: Option<String>,
    /// Z-map cell size, mm (0.05 for a fine check).
    #[arg(long, default_value_t = thinplan_stocksim::DEFAULT_CELL)]
    pub cell: f64,
    /// Tolerance for gouges and leftover, mm.
    #[arg(long, default_value_t = thinplan_stocksim::DEFAULT_TOL)]
    pub tol: f64,
    /// How near a part face may pass to a cell centre and not be judged
    /// there, mm (the part's tessellation error).
    #[arg(long, default_value_t = thinplan_stocksim::DEFAULT_WALL_TOL)]
    pub wall_tol: f64,
    /// Where the cells start, as a fraction of a cell past the blank's low
    /// corner in X and Y ([0, 1); 0.5: centres where the default grid has
    /// its corners).
    #[arg(long, default_value_t = 0.0)]
    pub grid_shift: f64,
    /// Report feed moves going down into stock steeper than this (degrees
    /// from horizontal) as plunges.
    #[arg(long)]
    pub max_descent_deg: Option<f64>,
    /// Print the report as JSON on stdout.
    #[arg(long)]
    pub json: bool,
    /// Write the top-view picture (SVG).
    #[arg(long)]
    pub svg: Option<PathBuf>,
}

/// Runs the simulation and prints the report. `Ok(true)` when clean: no
/// gouge, no missed leftover, no crash (unreachable leftover is allowed).
pub fn run(args: &SimulateArgs) -> Result<bool, String> {
    let part = thinplan_import::import(&args.part).map_err(|e| e.to_string())?;
    let prog_name = args.program.display().to_string();
    let bytes =
        std::fs::read(&args.program).map_err(|e| format!("{prog_name}: cannot read: {e}"))?;
    let program = parse_bytes(&bytes, &prog_name).map_err(|e| e.to_string())?;
    let table_path = match &args.tool_table {
        Some(p) => p.clone(),
        None => {
            let p = args
                .program
                .parent()
                .unwrap_or(Path::new("."))
                .join("tool.tbl");
            if !p.is_file() {
                return Err(format!(
                    "no tool table: pass --tool-table (no {} next to the program)",
                    p.display()
                ));
            }
            p
        }
    };
    let table_name = table_path.display().to_string();
    let table_text = std::fs::read_to_string(&table_path)
        .map_err(|e| format!("{table_name}: cannot read: {e}"))?;
    let tools = parse_tool_table(&table_text, &table_name).map_err(|e| e.to_string())?;
    let blank = args.blank.as_deref().map(Blank::parse).transpose()?;
    let cfg = SimConfig {
        cell: args.cell,
        tol: args.tol,
        wall_tol: args.wall_tol,
        grid_shift: args.grid_shift,
        blank,
        checks: thinplan_stocksim::MoveChecks {
            max_descent_deg: args.max_descent_deg,
            tol: args.tol,
            rim: args.wall_tol,
            ..Default::default()
        },
    };
    let sim = simulate(&part.brep, &program, &tools, &cfg).map_err(|e| e.to_string())?;
    if let Some(out) = &args.svg {
        std::fs::write(out, sim.svg())
            .map_err(|e| format!("{}: cannot write: {e}", out.display()))?;
    }
    let r = &sim.report;
    if args.json {
        println!(
            "{}",
            serde_json::to_string_pretty(r).map_err(|e| e.to_string())?
        );
    } else {
        print!("{}", summary(&args.part, &prog_name, r));
    }
    // Timing varies run to run: stderr, never the report.
    eprintln!(
        "replay: {} cells in {:.3} s ({:.1} M cells/s); comparison {:.3} s",
        r.cells_visited,
        sim.replay_time.as_secs_f64(),
        sim.cells_per_second() / 1e6,
        sim.compare_time.as_secs_f64()
    );
    Ok(r.clean)
}

fn defect(name: &str, d: &DefectSummary, out: &mut String) {
    if d.cells == 0 {
        let _ = writeln!(out, "  {name}: none");
        return;
    }
    let at = d.worst_at.unwrap_or([0.0; 2]);
    let line = d
        .worst_line
        .map(|l| format!(" (line {l})"))
        .unwrap_or_default();
    let _ = writeln!(
        out,
        "  {name}: {} cells in {} patches, {:.2} mm³, worst {:.3} mm at ({:.2}, {:.2}){line}",
        d.cells, d.regions_total, d.volume_mm3, d.worst_mm, at[0], at[1]
    );
}

fn summary(part: &str, prog: &str, r: &StockReport) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "simulate {part} {prog}: {} × {} cells of {} mm, tolerance {} mm",
        r.grid.nx, r.grid.ny, r.cell_mm, r.tolerance_mm
    );
    let _ = writeln!(
        s,
        "  program: {} moves, {} tool changes, feed {:.1} mm, rapid {:.1} mm",
        r.program.moves,
        r.program.tool_changes,
        r.program.feed_length_mm,
        r.program.rapid_length_mm
    );
    let _ = writeln!(
        s,
        "  removed {:.1} mm³; air cutting {:.1} % of the feed length ({:.1} mm)",
        r.removed_volume_mm3,
        r.air_cutting.share * 100.0,
        r.air_cutting.air_length_mm
    );
    if r.crashes.is_empty() {
        let _ = writeln!(s, "  crashes: none");
    }
    for c in &r.crashes {
        let _ = writeln!(
            s,
            "  crash: line {} {:?}, {:.3} mm deep at ({:.2}, {:.2}), {:.2} mm³",
            c.line, c.kind, c.depth_mm, c.at[0], c.at[1], c.volume_mm3
        );
    }
    defect("gouges", &r.gouges, &mut s);
    defect("leftover, missed", &r.leftover_missed, &mut s);
    defect("leftover, unreachable", &r.leftover_unreachable, &mut s);
    defect(
        "leftover, above reach (part unreachable, top shavable)",
        &r.leftover_above_reach,
        &mut s,
    );
    for w in &r.warnings {
        let _ = writeln!(s, "  warning: {w}");
    }
    let _ = writeln!(s, "{}", if r.clean { "CLEAN" } else { "NOT CLEAN" });
    s
}
