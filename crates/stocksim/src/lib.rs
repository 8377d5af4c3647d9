//! An independent stock simulation for thinplan's NC programs: it
//! reads the G-code text with its own reader ([`gcode`]), replays
//! it on a Z-map of a box blank with the real tool shapes ([`zmap`],
//! [`tools`]), and compares the result with the part's B-rep ([`compare`]):
//! gouges, leftover material (missed or unreachable), rapids into stock,
//! air-cutting share. It shares no code with the tool-path planner or the
//! post-processors, so it checks what they produced.
//!
//! Frame: the program's coordinates (any work offset G54–G59) are the
//! part's B-rep coordinates; the tool axis is +Z; Z is the tool tip.

pub mod compare;
pub mod gcode;
pub mod svg;
pub mod tools;
pub mod zmap;

use std::time::{Duration, Instant};

use serde::Serialize;
use thinplan_brep::Brep;

pub use compare::{CellClass, Region};
pub use gcode::{parse, parse_bytes, GcodeError, Move, MoveKind, Program};
pub use tools::{parse_tool_table, ToolKind, ToolLibrary, ToolShape};
pub use zmap::{Blank, Crash, CrashKind, Grid, MoveChecks, ReplayStats, SimError, ZMap};

/// Default cell size, mm.
pub const DEFAULT_CELL: f64 = 0.2;
/// The finer cell size for close checks, mm.
pub const FINE_CELL: f64 = 0.05;
/// Default comparison tolerance, mm.
pub const DEFAULT_TOL: f64 = 0.05;
/// Default wall tolerance, mm (see [`SimConfig::wall_tol`]).
pub const DEFAULT_WALL_TOL: f64 = 0.01;

/// Simulation settings.
#[derive(Debug, Clone, PartialEq)]
pub struct SimConfig {
    /// Cell size, mm.
    pub cell: f64,
    /// Tolerance for gouge and leftover, mm.
    pub tol: f64,
    /// How near a part face may pass to a cell centre and a cut there still
    /// not be a gouge, mm: the tessellation's error, not the gouge
    /// tolerance (a tool reaching `tol` into a wall would go unseen wherever
    /// the wall stood within `tol` of a row of centres). Material at a
    /// wall's foot is leftover only beyond `tol` of the wall.
    pub wall_tol: f64,
    /// Where the cells start, as a fraction of a cell past the blank's low
    /// corner in X and Y (`[0, 1)`; 0: at the corner).
    pub grid_shift: f64,
    /// The blank; `None` = the part's bounding box.
    pub blank: Option<Blank>,
    /// Plunges and shank contact to report as crashes (none by default).
    pub checks: MoveChecks,
}

impl Default for SimConfig {
    fn default() -> Self {
        SimConfig {
            cell: DEFAULT_CELL,
            tol: DEFAULT_TOL,
            wall_tol: DEFAULT_WALL_TOL,
            grid_shift: 0.0,
            blank: None,
            checks: MoveChecks::default(),
        }
    }
}

/// A tool the program used, for the report.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ToolUse {
    pub number: u32,
    pub kind: ToolKind,
    pub diameter: f64,
    pub corner_radius: f64,
}

/// Program totals.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ProgramStats {
    pub moves: usize,
    pub tool_changes: usize,
    pub feed_length_mm: f64,
    pub rapid_length_mm: f64,
}

/// Air cutting: feed moves that removed no material.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct AirCutting {
    pub air_length_mm: f64,
    /// `air_length / feed_length` (0 with no feed moves).
    pub share: f64,
}

/// Totals for one class of defect.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct DefectSummary {
    pub cells: usize,
    pub area_mm2: f64,
    /// Σ |stock − part| · cell area, mm³.
    pub volume_mm3: f64,
    /// The largest |stock − part|, mm (0 when none).
    pub worst_mm: f64,
    pub worst_at: Option<[f64; 2]>,
    /// Gouges: the line that last cut the worst cell.
    pub worst_line: Option<usize>,
    /// Patches, largest volume first (at most [`MAX_REGIONS`]).
    pub regions: Vec<Region>,
    pub regions_total: usize,
}

/// Most regions listed per class.
pub const MAX_REGIONS: usize = 20;

/// The simulation's findings. Field order is the JSON order; the values depend
/// only on the inputs.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct StockReport {
    /// No gouge, no missed leftover, no crash (leftover where no tool
    /// reaches the part, unreachable or above reach, is reported only).
    pub clean: bool,
    pub cell_mm: f64,
    pub tolerance_mm: f64,
    pub blank: Blank,
    pub grid: Grid,
    pub tools: Vec<ToolUse>,
    pub program: ProgramStats,
    pub removed_volume_mm3: f64,
    pub air_cutting: AirCutting,
    pub crashes: Vec<Crash>,
    /// Operations undone for a crash or gouge, with it (only when
    /// [`MoveChecks::operations`] names the operations).
    pub excluded: Vec<(u32, Crash)>,
    pub gouges: DefectSummary,
    /// Leftover a tool could have taken down to the part.
    pub leftover_missed: DefectSummary,
    /// Leftover where no tool reaches the part, measured down to the part.
    pub leftover_unreachable: DefectSummary,
    /// Leftover where no tool reaches the part but one could have taken
    /// some off the top ([`CellClass::AboveReach`]): measured down to what
    /// the tools could leave, as missed leftover is.
    pub leftover_above_reach: DefectSummary,
    /// Cells evaluated under the tool during the replay (a work measure).
    pub cells_visited: u64,
    pub cells_lowered: u64,
    pub warnings: Vec<String>,
}

/// A finished simulation: the report and the fields behind it.
#[derive(Debug, Clone)]
pub struct Simulation {
    pub report: StockReport,
    pub stock: ZMap,
    /// Part top height per cell.
    pub part: Vec<f32>,
    /// Lowest stock the program's tools could leave without gouging.
    pub ideal: Vec<f32>,
    pub classes: Vec<CellClass>,
    /// Wall time of the replay alone (not in the report: it varies).
    pub replay_time: Duration,
    /// Wall time of the comparison.
    pub compare_time: Duration,
}

impl Simulation {
    /// Replay speed, cells evaluated per second.
    pub fn cells_per_second(&self) -> f64 {
        self.report.cells_visited as f64 / self.replay_time.as_secs_f64().max(1e-9)
    }

    /// The top-view picture (SVG).
    pub fn svg(&self) -> String {
        svg::top_view(self)
    }
}

/// Replays `program` on a box blank and compares the stock with `part`.
pub fn simulate(
    part: &Brep,
    program: &Program,
    tools: &ToolLibrary,
    cfg: &SimConfig,
) -> Result<Simulation, SimError> {
    if !(cfg.tol.is_finite() && cfg.tol >= 0.0) {
        return Err(SimError(format!("tolerance {} must be ≥ 0", cfg.tol)));
    }
    let bbox = part.bbox();
    let mut warnings = program.warnings.clone();
    let blank = match cfg.blank {
        Some(b) => {
            let eps = 1e-6;
            if bbox.min.cmplt(b.min - eps).any() || bbox.max.cmpgt(b.max + eps).any() {
                warnings.push(format!(
                    "the part's box {:?}–{:?} is not inside the blank",
                    bbox.min.to_array(),
                    bbox.max.to_array()
                ));
            }
            b
        }
        None => {
            if !(bbox.min.is_finite() && bbox.max.is_finite()) {
                return Err(SimError("the part is empty: give a blank".into()));
            }
            Blank {
                min: bbox.min,
                max: bbox.max,
            }
        }
    };
    let mut stock = ZMap::shifted(blank, cfg.cell, cfg.grid_shift)?;
    let grid = stock.grid;
    let floor = blank.min.z as f32;
    let (field, pw) = compare::part_heights(part, &grid, blank.min.z, cfg.wall_tol, cfg.tol);
    warnings.extend(pw);
    if !cfg.checks.operations.is_empty() {
        // Operations are judged as they cut: a gouge undoes its operation.
        let tol = cfg.tol as f32;
        stock.guard = Some(field.lo.iter().map(|&l| l - tol).collect());
    }
    stock.faces = Some(field.face.clone());
    let t0 = Instant::now();
    let rs = stock.replay_checked(program, tools, &cfg.checks)?;
    let replay_time = t0.elapsed();
    warnings.extend(rs.warnings.iter().cloned());

    let t1 = Instant::now();
    let part_top = field.top.clone();
    let ideal = if rs.tools_used.is_empty() {
        part_top.clone()
    } else {
        // Where no part stands the tool may go below the blank (a through
        // opening is cut free, not down to its underside only): such
        // columns sit lower by the largest corner radius, and the ideal is
        // then held at the blank's underside, where the stock ends.
        let free = rs
            .tools_used
            .iter()
            .map(|t| tools[t].corner_radius)
            .fold(0.0, f64::max) as f32
            + 2.0 * cfg.cell as f32;
        let open: Vec<f32> = part_top
            .iter()
            .map(|&p| if p <= floor { floor - free } else { p })
            .collect();
        let mut best = vec![f32::INFINITY; grid.len()];
        for t in &rs.tools_used {
            let f = compare::ideal_field(&open, &grid, &tools[t], floor);
            for (b, v) in best.iter_mut().zip(f) {
                *b = b.min(v.max(floor));
            }
        }
        best
    };
    let classes = compare::classify(&stock.top, &field, &ideal, cfg.tol);
    // Missed and above-reach material is measured down to what the tools
    // could have reached, not to the part: a column no tool reaches whose
    // top a tool could have shaved counts the shaving only (above reach).
    let reachable: Vec<f32> = ideal
        .iter()
        .zip(&part_top)
        .map(|(i, p)| i.max(*p))
        .collect();
    let summary = |class| {
        let regs = compare::regions(
            &classes,
            class,
            &stock.top,
            if matches!(class, CellClass::Missed | CellClass::AboveReach) {
                &reachable
            } else {
                &part_top
            },
            &stock.last_line,
            &grid,
        );
        let cells: usize = regs.iter().map(|r| r.cells).sum();
        let worst = regs.iter().min_by(|a, b| {
            b.worst_mm
                .total_cmp(&a.worst_mm)
                .then(a.at[1].total_cmp(&b.at[1]))
                .then(a.at[0].total_cmp(&b.at[0]))
        });
        DefectSummary {
            cells,
            area_mm2: cells as f64 * grid.cell_area(),
            // `+ 0.0`: an empty float sum is −0.0.
            volume_mm3: regs.iter().map(|r| r.volume_mm3).sum::<f64>() + 0.0,
            worst_mm: worst.map_or(0.0, |r| r.worst_mm),
            worst_at: worst.map(|r| r.at),
            worst_line: worst.and_then(|r| r.line),
            regions_total: regs.len(),
            regions: regs.into_iter().take(MAX_REGIONS).collect(),
        }
    };
    let gouges = summary(CellClass::Gouge);
    let missed = summary(CellClass::Missed);
    let unreachable = summary(CellClass::Unreachable);
    let above_reach = summary(CellClass::AboveReach);
    let compare_time = t1.elapsed();

    let tool_uses = rs
        .tools_used
        .iter()
        .map(|t| {
            let s = tools[t];
            ToolUse {
                number: *t,
                kind: s.kind(),
                diameter: s.diameter,
                corner_radius: s.corner_radius,
            }
        })
        .collect();
    let report = StockReport {
        clean: gouges.cells == 0
            && missed.cells == 0
            && rs.crashes.is_empty()
            && rs.excluded.is_empty(),
        cell_mm: cfg.cell,
        tolerance_mm: cfg.tol,
        blank,
        grid,
        tools: tool_uses,
        program: ProgramStats {
            moves: program.moves.len(),
            tool_changes: program.tool_changes.len(),
            feed_length_mm: rs.feed_length,
            rapid_length_mm: rs.rapid_length,
        },
        removed_volume_mm3: rs.cut.volume,
        air_cutting: AirCutting {
            air_length_mm: rs.air_length,
            share: if rs.feed_length > 0.0 {
                rs.air_length / rs.feed_length
            } else {
                0.0
            },
        },
        crashes: rs.crashes,
        excluded: rs.excluded,
        gouges,
        leftover_missed: missed,
        leftover_unreachable: unreachable,
        leftover_above_reach: above_reach,
        cells_visited: rs.cut.visited,
        cells_lowered: rs.cut.lowered,
        warnings,
    };
    Ok(Simulation {
        report,
        stock,
        part: part_top,
        ideal,
        classes,
        replay_time,
        compare_time,
    })
}
