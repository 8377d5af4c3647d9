//! The Z-map (one dexel per cell along +Z): each cell of a regular XY grid
//! stores the height of the stock's top at the cell centre, and every move
//! lowers the cells its tool passes over.
//!
//! Sweeping is analytic per cell, not by stamping the tool at sub-steps:
//! - a straight move (any Z change) lowers each cell to the minimum over the
//!   move of `z(s) + h(ρ(s))` (tip height plus the tool profile at the
//!   horizontal distance ρ). For a flat end mill that is the tip height at one
//!   end of the interval where the cell is under the tool; for rounded tools
//!   the function is convex in `s` (a convex increasing profile of a convex
//!   distance, plus a linear term). A ball's minimum has a closed form; a
//!   bull-nose's is found by a few safeguarded Newton steps on the derivative
//!   to 1e-9 mm along the move (see [`min_convex`]). Exact at every cell
//!   centre.
//! - a constant-Z arc is exact too: the nearest point of the arc to a cell is
//!   radial if the cell's angle lies in the arc's span, else an end point.
//! - helical or spiral arcs (Z or radius changing) are cut into chords whose
//!   sagitta is at most ⅛ cell (a helix: at most 0.001 mm), each swept
//!   exactly as above, so the error is below ⅛ cell (< ¼ cell as required).
//!
//! The only discretisation is the grid itself: the stock is known at cell
//! centres, and volumes are sums of cell columns.

use std::collections::BTreeMap;

use glam::{DVec2, DVec3};
use serde::Serialize;

use crate::gcode::{Move, MoveKind, Program, Spindle};
use crate::tools::{ToolLibrary, ToolShape};

/// Most cells a grid may have (memory: 8 bytes a cell plus the comparison's).
pub const MAX_CELLS: usize = 60_000_000;

/// Depth below which a change is not counted as removed material, mm.
pub const REMOVAL_EPS: f64 = 1e-3;

/// A grid rim margin against floating-point grazing: a tool whose edge runs
/// exactly through a cell centre does not cut it.
const RIM_EPS: f64 = 1e-7;
/// End radii of a level arc this close are one circle (their mean): the
/// rounding of a program's coordinates, as LinuxCNC reads them.
const ARC_RADIUS_TOL: f64 = 0.002;
/// Sagitta of the chords a helix is swept by, mm: half the program's
/// rounding.
const HELIX_SAGITTA: f64 = 0.001;

/// An axis-aligned box blank, mm.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Blank {
    pub min: DVec3,
    pub max: DVec3,
}

impl Blank {
    /// Parses `"xmin,ymin,zmin,xmax,ymax,zmax"`.
    pub fn parse(s: &str) -> Result<Blank, String> {
        let v: Vec<f64> = s
            .split(',')
            .map(|t| t.trim().parse::<f64>())
            .collect::<Result<_, _>>()
            .map_err(|e| format!("blank `{s}`: {e} (expected xmin,ymin,zmin,xmax,ymax,zmax)"))?;
        if v.len() != 6 {
            return Err(format!(
                "blank `{s}`: expected 6 numbers xmin,ymin,zmin,xmax,ymax,zmax, got {}",
                v.len()
            ));
        }
        let b = Blank {
            min: DVec3::new(v[0], v[1], v[2]),
            max: DVec3::new(v[3], v[4], v[5]),
        };
        b.validate()?;
        Ok(b)
    }

    pub fn validate(&self) -> Result<(), String> {
        if !(self.min.is_finite() && self.max.is_finite()) {
            return Err("blank has a non-finite coordinate".into());
        }
        if self.min.cmpge(self.max).any() {
            return Err(format!(
                "blank min {:?} must be below max {:?} on every axis",
                self.min.to_array(),
                self.max.to_array()
            ));
        }
        Ok(())
    }
}

/// A regular grid of cells over the blank's XY; cell `(i, j)` has its centre
/// at `(x0 + (i + ½)·cell, y0 + (j + ½)·cell)`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Grid {
    pub x0: f64,
    pub y0: f64,
    pub cell: f64,
    pub nx: usize,
    pub ny: usize,
}

impl Grid {
    /// The grid covering `[min, max]` with square cells of `cell` mm.
    pub fn new(min: DVec2, max: DVec2, cell: f64) -> Result<Grid, String> {
        if !(cell.is_finite() && cell > 0.0) {
            return Err(format!("cell size {cell} must be positive"));
        }
        let ext = max - min;
        let nx = (ext.x / cell).ceil().max(1.0);
        let ny = (ext.y / cell).ceil().max(1.0);
        if nx * ny > MAX_CELLS as f64 || nx.is_nan() || ny.is_nan() {
            return Err(format!(
                "a {cell} mm grid over {:.1} × {:.1} mm has {nx} × {ny} cells, more than {MAX_CELLS}; use a larger cell",
                ext.x, ext.y
            ));
        }
        Ok(Grid {
            x0: min.x,
            y0: min.y,
            cell,
            nx: nx as usize,
            ny: ny as usize,
        })
    }

    pub fn len(&self) -> usize {
        self.nx * self.ny
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    #[inline]
    pub fn center(&self, i: usize, j: usize) -> DVec2 {
        DVec2::new(
            self.x0 + (i as f64 + 0.5) * self.cell,
            self.y0 + (j as f64 + 0.5) * self.cell,
        )
    }

    /// Indices of the cells whose centres lie in `[lo, hi]` along one axis.
    #[inline]
    fn range(origin: f64, cell: f64, n: usize, lo: f64, hi: f64) -> Option<(usize, usize)> {
        let a = ((lo - origin) / cell - 0.5).ceil().max(0.0);
        let b = ((hi - origin) / cell - 0.5).floor().min(n as f64 - 1.0);
        if a.is_nan() || b.is_nan() || a > b {
            None
        } else {
            Some((a as usize, b as usize))
        }
    }

    pub(crate) fn cols(&self, lo: f64, hi: f64) -> Option<(usize, usize)> {
        Self::range(self.x0, self.cell, self.nx, lo, hi)
    }

    pub(crate) fn rows(&self, lo: f64, hi: f64) -> Option<(usize, usize)> {
        Self::range(self.y0, self.cell, self.ny, lo, hi)
    }

    pub fn cell_area(&self) -> f64 {
        self.cell * self.cell
    }
}

/// What one sweep did.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct CutStats {
    /// Cells evaluated under the tool.
    pub visited: u64,
    /// Cells lowered.
    pub lowered: u64,
    /// Material removed, mm³.
    pub volume: f64,
    /// Deepest cut in one cell, mm.
    pub max_depth: f64,
    /// Where that was (cell centre, new height).
    pub deepest: DVec3,
    /// Deepest cut in a cell but the slivers on part faces
    /// ([`ZMap::faces`]), mm: what the plunge and shank checks judge.
    pub core_depth: f64,
    /// Deepest cut below the guard ([`ZMap::guard`]), mm, and where.
    pub gouge: f64,
    pub gouge_at: DVec3,
}

impl CutStats {
    fn add(&mut self, o: &CutStats) {
        self.visited += o.visited;
        self.lowered += o.lowered;
        self.volume += o.volume;
        if o.max_depth > self.max_depth {
            self.max_depth = o.max_depth;
            self.deepest = o.deepest;
        }
        self.core_depth = self.core_depth.max(o.core_depth);
        if o.gouge > self.gouge {
            self.gouge = o.gouge;
            self.gouge_at = o.gouge_at;
        }
    }

    /// Whether the move removed material (deeper than [`REMOVAL_EPS`]).
    pub fn removed(&self) -> bool {
        self.max_depth > REMOVAL_EPS
    }
}

/// Why a move is reported as a crash.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum CrashKind {
    /// A G0 that removes material.
    RapidIntoStock,
    /// A feed move that removes material with the spindle stopped.
    SpindleOff,
    /// A feed move going down into material steeper than the entry limit
    /// ([`MoveChecks::max_descent_deg`]): an axial plunge, not a ramp or helix.
    PlungeIntoStock,
    /// A feed move that cuts a column of material taller than the tool's
    /// flute length ([`MoveChecks::flute_length`]): the shank cuts.
    ShankContact,
    /// A move that cuts below the part (only with a guard, see
    /// [`MoveChecks::operations`]).
    Gouge,
}

/// Checks of the moves themselves, beside the stock they leave. The default
/// checks nothing beyond rapids and a stopped spindle.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct MoveChecks {
    /// Flute length per tool number, mm: a column cut deeper than this in
    /// one move had material above the flutes (the tip is at or below the
    /// column's new height, so this never over-reports).
    pub flute_length: BTreeMap<u32, f64>,
    /// Steepest descent into material a feed move may make, degrees from
    /// horizontal; `None` checks no descent.
    pub max_descent_deg: Option<f64>,
    /// A steeper descent removing no more than this (mm³) is a graze, not
    /// a plunge.
    pub max_plunge_mm3: f64,
    /// Cuts shallower than this (mm) are not counted as plunges or shank
    /// contact: the comparison tolerance.
    pub tol: f64,
    /// A cell on a part face ([`ZMap::faces`]) the tool's edge reaches by
    /// no more than this (mm) is not counted as a plunge or shank contact:
    /// it stands for a sliver a faceted face left, not for a column.
    pub rim: f64,
    /// The program's operations, `(first line, id)` in line order. When
    /// given, an operation one of whose moves crashes (or, with a guard,
    /// gouges) is undone and the rest of it skipped, so that the operations
    /// after it are judged on the stock the program without it leaves; the
    /// link into the next operation, which would then start elsewhere, is
    /// not swept. [`ReplayStats::excluded`] lists them.
    pub operations: Vec<(usize, u32)>,
}

impl MoveChecks {
    fn plunges(&self, m: &Move, start: DVec3, st: &CutStats) -> bool {
        let Some(limit) = self.max_descent_deg else {
            return false;
        };
        let drop = start.z - m.end.z;
        if drop <= 1e-9
            || st.core_depth <= self.tol.max(REMOVAL_EPS)
            || st.volume <= self.max_plunge_mm3
        {
            return false;
        }
        // Arcs descend along their length; lines along their plan length.
        let run = match m.kind {
            MoveKind::Arc { .. } => (m.length().powi(2) - drop * drop).max(0.0).sqrt(),
            _ => (m.end.truncate() - start.truncate()).length(),
        };
        drop.atan2(run).to_degrees() > limit + 1e-6
    }

    fn shank(&self, tool: u32, st: &CutStats) -> bool {
        self.flute_length
            .get(&tool)
            .is_some_and(|&l| st.core_depth > l + self.tol)
    }
}

/// A move that cut where it must not.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Crash {
    pub line: usize,
    pub kind: CrashKind,
    pub volume_mm3: f64,
    pub depth_mm: f64,
    /// Cell centre and new height of the deepest cut.
    pub at: [f64; 3],
}

/// The totals of a replay.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ReplayStats {
    pub cut: CutStats,
    pub feed_length: f64,
    pub rapid_length: f64,
    /// Feed length of moves that removed no material.
    pub air_length: f64,
    pub crashes: Vec<Crash>,
    /// Tools that made feed moves, ascending.
    pub tools_used: Vec<u32>,
    /// Operations undone for a crash, with it (see [`MoveChecks::operations`]).
    pub excluded: Vec<(u32, Crash)>,
    pub warnings: Vec<String>,
}

/// An error that stops a replay.
#[derive(Debug, Clone, PartialEq)]
pub struct SimError(pub String);

impl std::fmt::Display for SimError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for SimError {}

/// The stock as a Z-map.
#[derive(Debug, Clone)]
pub struct ZMap {
    pub grid: Grid,
    pub blank: Blank,
    /// Stock top per cell (row-major, `j * nx + i`), mm.
    pub top: Vec<f32>,
    /// The program line that last lowered each cell (0 = never cut).
    pub last_line: Vec<u32>,
    /// The lowest each cell may be cut without a gouge (the part less the
    /// tolerance); a cut below it is reported in [`CutStats::gouge`].
    pub guard: Option<Vec<f32>>,
    /// Cells a part face passes within the wall tolerance of. There a cut
    /// only within [`MoveChecks::rim`] of the tool's edge takes a sliver
    /// left on the face (no thicker than the two together), not a column:
    /// it is no plunge or shank contact. `None`: no cell is such a cell.
    pub faces: Option<Vec<bool>>,
    /// While an operation is replayed in exclusion mode: each cell's state
    /// before its first change, to undo it.
    undo: Option<Vec<(usize, f32, u32)>>,
    /// Per cell, the undo generation that saved it last: each cell is saved
    /// once per operation.
    saved: Vec<u32>,
    generation: u32,
    /// Where the last sweep left the tool (tip, radius, corner radius): the
    /// cells under it are already as low as that tool there makes them, so
    /// the next move from that point need not visit them again.
    last_end: Option<(DVec3, f64, f64)>,
    /// The rim band of [`MoveChecks::rim`] the replay judges with.
    rim: f64,
}

impl ZMap {
    /// A full box blank with cells of `cell` mm.
    pub fn new(blank: Blank, cell: f64) -> Result<ZMap, SimError> {
        ZMap::shifted(blank, cell, 0.0)
    }

    /// The Z-map of `blank` whose cells start `shift` of a cell (in
    /// `[0, 1)`) past the blank's low corner in X and Y: a second grid
    /// shifted by half a cell has its centres where the first one's
    /// corners are, and sees the fins narrower than a cell it may miss.
    pub fn shifted(blank: Blank, cell: f64, shift: f64) -> Result<ZMap, SimError> {
        blank.validate().map_err(SimError)?;
        if !(0.0..1.0).contains(&shift) {
            return Err(SimError(format!(
                "grid shift {shift} must be at least 0 and less than 1 (a fraction of a cell)"
            )));
        }
        let min = blank.min.truncate() + DVec2::splat(shift * cell);
        let max = blank.max.truncate().max(min);
        let grid = Grid::new(min, max, cell).map_err(SimError)?;
        Ok(ZMap {
            grid,
            blank,
            top: vec![blank.max.z as f32; grid.len()],
            last_line: vec![0; grid.len()],
            guard: None,
            faces: None,
            undo: None,
            saved: Vec::new(),
            generation: 0,
            last_end: None,
            rim: 0.0,
        })
    }

    /// Stock volume, mm³.
    pub fn volume(&self) -> f64 {
        let z0 = self.blank.min.z;
        self.top.iter().map(|&z| z as f64 - z0).sum::<f64>() * self.grid.cell_area()
    }

    /// Stock height at the cell containing `p` (None outside the grid).
    pub fn height_at(&self, p: DVec2) -> Option<f64> {
        let g = &self.grid;
        let i = ((p.x - g.x0) / g.cell).floor();
        let j = ((p.y - g.y0) / g.cell).floor();
        if i < 0.0 || j < 0.0 || i >= g.nx as f64 || j >= g.ny as f64 {
            return None;
        }
        Some(self.top[j as usize * g.nx + i as usize] as f64)
    }

    /// Lowers cell `(i, j)` to `z`; `core` when the cell's centre is
    /// farther than the rim band inside the tool's edge (see
    /// [`ZMap::faces`]).
    #[inline]
    fn lower(&mut self, i: usize, j: usize, z: f64, line: u32, core: bool, st: &mut CutStats) {
        st.visited += 1;
        let k = j * self.grid.nx + i;
        let z = z.max(self.blank.min.z) as f32;
        let cur = self.top[k];
        if z < cur {
            let depth = (cur - z) as f64;
            if let Some(u) = self.undo.as_mut() {
                if self.saved[k] != self.generation {
                    self.saved[k] = self.generation;
                    u.push((k, cur, self.last_line[k]));
                }
            }
            if depth > 1e-6 {
                st.lowered += 1;
                st.volume += depth * self.grid.cell_area();
                self.last_line[k] = line;
            }
            self.top[k] = z;
            if let Some(g) = self.guard.as_ref() {
                let below = (g[k] - z) as f64;
                if below > st.gouge {
                    st.gouge = below;
                    let c = self.grid.center(i, j);
                    st.gouge_at = DVec3::new(c.x, c.y, z as f64);
                }
            }
            if depth > st.max_depth {
                st.max_depth = depth;
                let c = self.grid.center(i, j);
                st.deepest = DVec3::new(c.x, c.y, z as f64);
            }
            let sliver = !core && self.faces.as_ref().is_some_and(|f| f[k]);
            if !sliver && depth > st.core_depth {
                st.core_depth = depth;
            }
        }
    }

    /// Sweeps `tool` with its tip along the straight segment `p0 → p1`.
    pub fn sweep_line(&mut self, tool: &ToolShape, p0: DVec3, p1: DVec3, line: u32) -> CutStats {
        let st = self.sweep_line_from(tool, p0, p1, line);
        self.last_end = Some((p1, tool.radius(), tool.corner_radius));
        st
    }

    fn sweep_line_from(&mut self, tool: &ToolShape, p0: DVec3, p1: DVec3, line: u32) -> CutStats {
        let mut st = CutStats::default();
        let r = tool.radius() - RIM_EPS;
        if r <= 0.0 {
            return st;
        }
        if p0.z.min(p1.z) >= self.blank.max.z {
            // Stock never stands above the blank's top.
            return st;
        }
        let (a, b) = (p0.truncate(), p1.truncate());
        let d = b - a;
        let len = d.length();
        let Some((j0, j1)) = self.grid.rows(a.y.min(b.y) - r, a.y.max(b.y) + r) else {
            return st;
        };
        let flat = tool.corner_radius <= 0.0;
        if len < 1e-9 {
            // A plunge: the lowest tip height applies under the whole tool.
            let z = p0.z.min(p1.z);
            for j in j0..=j1 {
                let yc = self.grid.center(0, j).y;
                let dy = yc - a.y;
                let half2 = r * r - dy * dy;
                if half2 < 0.0 {
                    continue;
                }
                let half = half2.sqrt();
                let Some((i0, i1)) = self.grid.cols(a.x - half, a.x + half) else {
                    continue;
                };
                for i in i0..=i1 {
                    if self.top[j * self.grid.nx + i] as f64 <= z {
                        continue;
                    }
                    let rho = (self.grid.center(i, j) - a).length();
                    if let Some(h) = tool.height_at(rho.min(tool.radius())) {
                        let core = rho <= tool.radius() - self.rim;
                        self.lower(i, j, z + h, line, core, &mut st);
                    }
                }
            }
            return st;
        }
        let u = d / len;
        let k = (p1.z - p0.z) / len;
        // A level or rising move from where the same tool last stood: the
        // cells whose nearest point of the move is its start keep the height
        // that stand gave them (for a flat end, every cell under it).
        let from_last = k >= 0.0 && self.last_end == Some((p0, tool.radius(), tool.corner_radius));
        let r_in = r - 1e-9;
        let z_low = p0.z.min(p1.z);
        for j in j0..=j1 {
            let yc = self.grid.center(0, j).y;
            let Some((xlo, xhi)) = capsule_row(a, b, u, len, r, yc) else {
                continue;
            };
            let Some((i0, i1)) = self.grid.cols(xlo, xhi) else {
                continue;
            };
            let (sl, sh) = if from_last {
                start_disc_row(a, u, r_in, yc, flat)
            } else {
                (f64::INFINITY, f64::NEG_INFINITY)
            };
            let row = j * self.grid.nx;
            for i in i0..=i1 {
                // The tool stands nowhere lower than its lowest tip: a cell
                // already at or below it cannot be cut.
                if self.top[row + i] as f64 <= z_low {
                    continue;
                }
                let xc = self.grid.x0 + (i as f64 + 0.5) * self.grid.cell;
                if xc > sl && xc < sh {
                    continue;
                }
                let w = self.grid.center(i, j) - a;
                let s0 = w.dot(u);
                let perp = w.perp_dot(u).abs();
                if perp > r {
                    continue;
                }
                let half = (r * r - perp * perp).sqrt();
                let lo = (s0 - half).max(0.0);
                let hi = (s0 + half).min(len);
                if lo > hi {
                    continue;
                }
                let z = if flat {
                    p0.z + k * if k >= 0.0 { lo } else { hi }
                } else {
                    let s = min_convex(tool, k, perp, s0, lo, hi);
                    let rho = (perp * perp + (s - s0) * (s - s0))
                        .sqrt()
                        .min(tool.radius());
                    p0.z + k * s + tool.height_at(rho).unwrap_or(0.0)
                };
                // Nearest the axis comes to the cell along the move.
                let near = if s0 < 0.0 {
                    w.length()
                } else if s0 > len {
                    (self.grid.center(i, j) - b).length()
                } else {
                    perp
                };
                let core = near <= tool.radius() - self.rim;
                self.lower(i, j, z, line, core, &mut st);
            }
        }
        st
    }

    /// Sweeps `tool` along an arc at constant Z from `s` turning `sweep` rad
    /// (positive counter-clockwise) about `center`.
    #[allow(clippy::too_many_arguments)]
    fn sweep_flat_arc(
        &mut self,
        tool: &ToolShape,
        center: DVec2,
        s: DVec2,
        e: DVec2,
        ra: f64,
        sweep: f64,
        z: f64,
        line: u32,
    ) -> CutStats {
        let mut st = CutStats::default();
        let r = tool.radius() - RIM_EPS;
        // Counter-clockwise from `from` by `span`.
        let (from, span) = if sweep >= 0.0 {
            (s, sweep)
        } else {
            (e, -sweep)
        };
        let a0 = (from - center).to_angle();
        let (mut lo, mut hi) = (s.min(e), s.max(e));
        for q in 0..4 {
            let ang = q as f64 * std::f64::consts::FRAC_PI_2;
            if (ang - a0).rem_euclid(std::f64::consts::TAU) <= span {
                let p = center + ra * DVec2::from_angle(ang);
                lo = lo.min(p);
                hi = hi.max(p);
            }
        }
        let Some((j0, j1)) = self.grid.rows(lo.y - r, hi.y + r) else {
            return st;
        };
        let Some((i0, i1)) = self.grid.cols(lo.x - r, hi.x + r) else {
            return st;
        };
        for j in j0..=j1 {
            for i in i0..=i1 {
                if self.top[j * self.grid.nx + i] as f64 <= z {
                    continue;
                }
                let c = self.grid.center(i, j);
                let v = c - center;
                let rho_c = v.length();
                if (rho_c - ra).abs() > r {
                    continue;
                }
                let in_span = rho_c > 1e-12
                    && (v.to_angle() - a0).rem_euclid(std::f64::consts::TAU) <= span + 1e-12;
                let dist = if in_span {
                    (rho_c - ra).abs()
                } else if rho_c <= 1e-12 {
                    ra
                } else {
                    (c - s).length().min((c - e).length())
                };
                if dist > r {
                    continue;
                }
                if let Some(h) = tool.height_at(dist) {
                    let core = dist <= tool.radius() - self.rim;
                    self.lower(i, j, z + h, line, core, &mut st);
                }
            }
        }
        st
    }

    /// Sweeps one canonical move (see the module doc for the accuracy).
    pub fn sweep_move(&mut self, tool: &ToolShape, m: &Move, start: DVec3) -> CutStats {
        let line = m.line.min(u32::MAX as usize) as u32;
        match m.kind {
            MoveKind::Rapid | MoveKind::Line => self.sweep_line(tool, start, m.end, line),
            MoveKind::Arc { center, sweep, .. } => {
                let (s, e) = (start.truncate(), m.end.truncate());
                let r0 = (s - center).length();
                let r1 = (e - center).length();
                // A program's coordinates are rounded (0.001 mm): its arcs'
                // end radii differ by that much, and chords would sweep
                // them up to a cell/8 inside the arc.
                if (m.end.z - start.z).abs() < 1e-9 && (r0 - r1).abs() <= ARC_RADIUS_TOL {
                    let ra = 0.5 * (r0 + r1);
                    let st = self.sweep_flat_arc(tool, center, s, e, ra, sweep, start.z, line);
                    self.last_end = Some((e.extend(start.z), tool.radius(), tool.corner_radius));
                    return st;
                }
                // Helix or spiral: chords with sagitta ≤ cell/8; a helix
                // (a ramp beside level arcs of its own radius) within the
                // program's rounding, so it cuts no more inside them.
                let sag = if (r0 - r1).abs() <= ARC_RADIUS_TOL {
                    (self.grid.cell / 8.0).min(HELIX_SAGITTA)
                } else {
                    self.grid.cell / 8.0
                };
                let rmax = r0.max(r1);
                let step = if sag >= rmax {
                    std::f64::consts::FRAC_PI_2
                } else {
                    (2.0 * (1.0 - sag / rmax).acos()).min(std::f64::consts::FRAC_PI_2)
                };
                let n = ((sweep.abs() / step).ceil() as usize).clamp(1, 1 << 20);
                let a0 = (s - center).to_angle();
                let mut st = CutStats::default();
                let mut prev = start;
                for q in 1..=n {
                    let t = q as f64 / n as f64;
                    let p = if q == n {
                        m.end
                    } else {
                        let rad = r0 + (r1 - r0) * t;
                        let xy = center + rad * DVec2::from_angle(a0 + sweep * t);
                        xy.extend(start.z + (m.end.z - start.z) * t)
                    };
                    st.add(&self.sweep_line(tool, prev, p, line));
                    prev = p;
                }
                st
            }
        }
    }

    /// Replays a whole program.
    pub fn replay(
        &mut self,
        program: &Program,
        tools: &ToolLibrary,
    ) -> Result<ReplayStats, SimError> {
        self.replay_checked(program, tools, &MoveChecks::default())
    }

    /// Replays a whole program and reports, beside rapids into stock and a
    /// stopped spindle, the moves `checks` forbids.
    pub fn replay_checked(
        &mut self,
        program: &Program,
        tools: &ToolLibrary,
        checks: &MoveChecks,
    ) -> Result<ReplayStats, SimError> {
        let mut out = ReplayStats::default();
        self.rim = checks.rim.max(0.0);
        let mut used = std::collections::BTreeSet::new();
        let mut warned_no_tool = false;
        let ops = &checks.operations;
        let exclusion = !ops.is_empty();
        // The operation of the current move (index into `ops`), whether it
        // is excluded, and whether the one before it was (its successor's
        // link then starts where the program without it would not).
        let mut cur: Option<usize> = None;
        let mut skip_op = false;
        let mut after_excluded = false;
        let mut fed_in_op = false;
        for m in &program.moves {
            if exclusion {
                let k = ops.partition_point(|(l, _)| *l <= m.line);
                let now = k.checked_sub(1);
                if now != cur {
                    after_excluded = skip_op;
                    skip_op = false;
                    fed_in_op = false;
                    cur = now;
                    self.begin_undo(now.is_some());
                }
                if skip_op {
                    continue;
                }
                if m.is_feed() {
                    fed_in_op = true;
                }
                if after_excluded && !fed_in_op && !m.is_feed() {
                    continue;
                }
            }
            if !m.end.is_finite() {
                continue; // only some axes known yet: nothing to sweep
            }
            let len = m.length();
            if m.is_feed() {
                out.feed_length += len;
            } else {
                out.rapid_length += len;
            }
            let start = if m.positioning() {
                // Brought in from above the stock.
                let above = m.end.z.max(self.blank.max.z + 1.0);
                DVec3::new(
                    if m.start.x.is_finite() {
                        m.start.x
                    } else {
                        m.end.x
                    },
                    if m.start.y.is_finite() {
                        m.start.y
                    } else {
                        m.end.y
                    },
                    if m.start.z.is_finite() {
                        m.start.z
                    } else {
                        above
                    },
                )
            } else {
                m.start
            };
            let Some(t) = m.tool else {
                if m.is_feed() && !warned_no_tool {
                    warned_no_tool = true;
                    out.warnings.push(format!(
                        "line {}: feed move with no tool in the spindle (not simulated)",
                        m.line
                    ));
                }
                continue;
            };
            let Some(shape) = tools.get(&t) else {
                return Err(SimError(format!(
                    "line {}: tool T{t} has no shape (give it in the tool table)",
                    m.line
                )));
            };
            if m.is_feed() {
                used.insert(t);
            }
            let st = self.sweep_move(shape, m, start);
            out.cut.add(&st);
            let crash = if !st.removed() {
                if m.is_feed() {
                    out.air_length += len;
                }
                None
            } else if !m.is_feed() {
                Some(CrashKind::RapidIntoStock)
            } else if m.spindle == Spindle::Off {
                Some(CrashKind::SpindleOff)
            } else if checks.plunges(m, start, &st) {
                Some(CrashKind::PlungeIntoStock)
            } else if checks.shank(t, &st) {
                Some(CrashKind::ShankContact)
            } else {
                None
            };
            let crash = crash.map(|kind| Crash {
                line: m.line,
                kind,
                volume_mm3: st.volume,
                depth_mm: st.max_depth,
                at: st.deepest.to_array(),
            });
            let gouge = (st.gouge > checks.tol.max(REMOVAL_EPS)).then(|| Crash {
                line: m.line,
                kind: CrashKind::Gouge,
                volume_mm3: 0.0,
                depth_mm: st.gouge,
                at: st.gouge_at.to_array(),
            });
            match (cur, crash.or(gouge)) {
                (Some(k), Some(c)) if exclusion => {
                    self.undo_operation();
                    out.excluded.push((ops[k].1, c));
                    skip_op = true;
                }
                (_, Some(c)) if c.kind != CrashKind::Gouge => out.crashes.push(c),
                _ => {}
            }
        }
        self.undo = None;
        out.tools_used = used.into_iter().collect();
        Ok(out)
    }

    /// Starts saving cells for a new operation (or stops, outside one).
    fn begin_undo(&mut self, on: bool) {
        if self.saved.len() != self.top.len() {
            self.saved = vec![0; self.top.len()];
        }
        self.generation = self.generation.wrapping_add(1);
        if self.generation == 0 {
            self.saved.fill(0);
            self.generation = 1;
        }
        self.undo = on.then(Vec::new);
    }

    /// Restores every cell the current operation changed.
    fn undo_operation(&mut self) {
        // Restored cells may stand above where the tool last was.
        self.last_end = None;
        if let Some(u) = self.undo.take() {
            for &(k, top, line) in u.iter() {
                self.top[k] = top;
                self.last_line[k] = line;
            }
        }
        self.begin_undo(true);
    }
}

/// The open x-interval of row `y` whose cells a move starting at `a` in
/// direction `u` leaves as the tool standing at `a` (radius `r`) left them:
/// the whole disc for a flat end; else the half of it behind `a`, where `a`
/// stays the move's nearest point. Empty as `(∞, −∞)`.
#[inline]
fn start_disc_row(a: DVec2, u: DVec2, r: f64, y: f64, flat: bool) -> (f64, f64) {
    const EMPTY: (f64, f64) = (f64::INFINITY, f64::NEG_INFINITY);
    let dy = y - a.y;
    let h2 = r * r - dy * dy;
    if h2 <= 0.0 {
        return EMPTY;
    }
    let h = h2.sqrt();
    let (mut lo, mut hi) = (a.x - h, a.x + h);
    if !flat {
        // Behind a: (x − a.x)·u.x + dy·u.y ≤ 0.
        let c = -dy * u.y;
        if u.x > 1e-12 {
            hi = hi.min(a.x + c / u.x);
        } else if u.x < -1e-12 {
            lo = lo.max(a.x + c / u.x);
        } else if c < 0.0 {
            return EMPTY;
        }
    }
    (lo, hi)
}

/// The x-interval of the capsule (segment `a→b` grown by `r`) on the row `y`.
#[inline]
fn capsule_row(a: DVec2, b: DVec2, u: DVec2, len: f64, r: f64, y: f64) -> Option<(f64, f64)> {
    let mut lo = f64::INFINITY;
    let mut hi = f64::NEG_INFINITY;
    for c in [a, b] {
        let dy = y - c.y;
        let h2 = r * r - dy * dy;
        if h2 >= 0.0 {
            let h = h2.sqrt();
            lo = lo.min(c.x - h);
            hi = hi.max(c.x + h);
        }
    }
    // The band: 0 ≤ (p−a)·u ≤ len and |(p−a)×u| ≤ r, each linear in x.
    let dy = y - a.y;
    let mut blo = f64::NEG_INFINITY;
    let mut bhi = f64::INFINITY;
    let mut ok = true;
    // (x−ax)·ux + dy·uy ∈ [0, len]
    for (coef, off, l, h) in [(u.x, dy * u.y, 0.0, len), (-u.y, dy * u.x, -r, r)] {
        // (x−ax)·coef + off ∈ [l, h]  (the cross product: (x−ax)·uy − dy·ux, negated)
        if coef.abs() < 1e-15 {
            if off < l || off > h {
                ok = false;
            }
        } else {
            let (x1, x2) = ((l - off) / coef, (h - off) / coef);
            blo = blo.max(x1.min(x2) + a.x);
            bhi = bhi.min(x1.max(x2) + a.x);
        }
    }
    if ok && blo <= bhi {
        lo = lo.min(blo);
        hi = hi.max(bhi);
    }
    (lo <= hi).then_some((lo, hi))
}

/// Minimises the convex `k·s + h(√(perp² + (s−s0)²))` over `[lo, hi]`:
/// the lowest point of the tool's lower envelope over the cell on a ramp.
///
/// In the tool's frame (`t = s − s0`) this is the point of slope `−k` on the
/// tool's section by the vertical plane at `perp` from its axis. For a ball
/// that section is a circle and the point has a closed form. A bull-nose's
/// section is a spiric curve (its tangent is a quartic): the minimiser lies
/// where the corner torus is under the cell (the flat core only rises with
/// `k·s`), so a safeguarded Newton iteration on the derivative, bracketed
/// there and started at the perp = 0 solution, converges in a few steps.
#[inline]
pub(crate) fn min_convex(tool: &ToolShape, k: f64, perp: f64, s0: f64, lo: f64, hi: f64) -> f64 {
    if k == 0.0 {
        return s0.clamp(lo, hi);
    }
    let rc = tool.corner_radius;
    let core = tool.radius() - rc;
    let (tlo, thi) = (lo - s0, hi - s0);
    if core <= 1e-12 {
        // Ball: d/dt [k·t − √(q² − t²)] = 0 at t = −k·q/√(1 + k²).
        let q = (rc * rc - perp * perp).max(0.0).sqrt();
        let t = -k * q / (1.0 + k * k).sqrt();
        return s0 + t.clamp(tlo, thi);
    }
    let deriv = |t: f64| -> (f64, f64) {
        // (F'(t), F''(t)) with F(t) = k·t + h(ρ), ρ = √(perp² + t²).
        // Not `hypot`: libm's is several times slower and mm scales cannot overflow.
        let rho = (perp * perp + t * t).sqrt();
        if rho <= core {
            return (k, 0.0);
        }
        let u = rho - core;
        let w2 = rc * rc - u * u;
        if w2 <= 0.0 {
            let inf = if t > 0.0 {
                f64::INFINITY
            } else {
                f64::NEG_INFINITY
            };
            return (inf, f64::INFINITY);
        }
        let w = w2.sqrt();
        let h1 = u / w; // h'(ρ)
        let h2 = rc * rc / (w2 * w); // h''(ρ)
        let c = t / rho;
        (
            k + h1 * c,
            h2 * c * c + h1 * perp * perp / (rho * rho * rho),
        )
    };
    // Where the flat core is under the cell, F' = k: the minimiser is on the
    // corner side that the ramp descends towards.
    let flat_half = (core * core - perp * perp).max(0.0).sqrt();
    let (mut a, mut b) = if k > 0.0 {
        (tlo, thi.min(-flat_half))
    } else {
        (tlo.max(flat_half), thi)
    };
    if a >= b {
        return s0 + if k > 0.0 { a.min(thi) } else { b.max(tlo) };
    }
    if deriv(a).0 >= 0.0 {
        return s0 + a;
    }
    if deriv(b).0 <= 0.0 {
        return s0 + b;
    }
    // Start at the solution for perp = 0: h'(ρ) = |k|.
    let u0 = rc * k.abs() / (1.0 + k * k).sqrt();
    let rho0 = core + u0;
    let mut t = -k.signum() * (rho0 * rho0 - perp * perp).max(0.0).sqrt();
    if !(t > a && t < b) {
        t = 0.5 * (a + b);
    }
    for _ in 0..60 {
        let (g, g1) = deriv(t);
        if g == 0.0 {
            break;
        }
        if g < 0.0 {
            a = t;
        } else {
            b = t;
        }
        let mut next = t - g / g1;
        if !(next > a && next < b) {
            next = 0.5 * (a + b);
        }
        let step = (next - t).abs();
        t = next;
        // F is flat at its minimum: 1e-9 mm along the move is exact in height.
        if step < 1e-9 || b - a < 1e-9 {
            break;
        }
    }
    s0 + t
}
