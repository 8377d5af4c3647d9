//! Benchmark: curvilinear vs parallel-offset (vs FreeCAD Adaptive) machining time over L/D.

use cavalier_contours::polyline::{PlineSourceMut, Polyline};
use glam::DVec2;
use serde::{Deserialize, Serialize};
use std::path::PathBuf;

use crate::engagement::{engagement_stats, EngagementParams, EngagementStats, Entry};
use crate::geom::{point_in_loop, sample_pline, SegIndex};
use crate::timing::{time_path, MachineLimits};
use crate::{
    curvilinear_path, offset_path, offset_path_gap_matched, offset_path_sharp, zigzag_path, Pocket,
    PocketError, PocketParams, PocketPath,
};

/// A convex polygon (counter-clockwise vertices) with every corner rounded by radius `rc`.
pub fn rounded_polygon(vertices: &[DVec2], rc: f64) -> Polyline<f64> {
    let n = vertices.len();
    let mut pl = Polyline::new_closed();
    for i in 0..n {
        let v = vertices[i];
        let prev = vertices[(i + n - 1) % n];
        let next = vertices[(i + 1) % n];
        let a = (prev - v).normalize();
        let b = (next - v).normalize();
        let interior = a.dot(b).clamp(-1.0, 1.0).acos();
        let t = rc / (interior / 2.0).tan();
        let turn = std::f64::consts::PI - interior;
        let p_in = v + a * t;
        let p_out = v + b * t;
        pl.add(p_in.x, p_in.y, (turn / 4.0).tan());
        pl.add(p_out.x, p_out.y, 0.0);
    }
    pl
}

/// Circle of diameter `d` centred at the origin.
pub fn circle(d: f64) -> Polyline<f64> {
    let mut pl = Polyline::new_closed();
    pl.add(d / 2.0, 0.0, 1.0);
    pl.add(-d / 2.0, 0.0, 1.0);
    pl
}

/// Rounded rectangle `w` × `h`, corner radius `rc`, centred at the origin.
pub fn rounded_rect(w: f64, h: f64, rc: f64) -> Polyline<f64> {
    let (x, y) = (w / 2.0, h / 2.0);
    rounded_polygon(
        &[
            DVec2::new(-x, -y),
            DVec2::new(x, -y),
            DVec2::new(x, y),
            DVec2::new(-x, y),
        ],
        rc,
    )
}

/// Regular n-gon with circumradius `rho` (a vertex at the top), corners rounded by `rc`.
pub fn rounded_ngon(n: usize, rho: f64, rc: f64) -> Polyline<f64> {
    let v: Vec<DVec2> = (0..n)
        .map(|i| {
            let a = std::f64::consts::FRAC_PI_2 + std::f64::consts::TAU * i as f64 / n as f64;
            rho * DVec2::from_angle(a)
        })
        .collect();
    rounded_polygon(&v, rc)
}

/// A bench pocket shape at characteristic size `l` (largest bounding-box side), with the
/// narrowest width `w` of the shape (used to size the tool).
#[derive(Debug, Clone)]
pub struct BenchPocket {
    pub pocket: Pocket,
    pub width: f64,
}

/// The bench family at size `l`: circle, rounded square, Bieterman's rounded pentagon, an
/// isogrid triangle with rounded corners, a slot-like rounded rectangle (4:1).
pub fn bench_family(l: f64) -> Vec<BenchPocket> {
    let pent_rho = l / (2.0 * 72f64.to_radians().sin());
    let tri_rho = l / 3f64.sqrt(); // side l
    vec![
        BenchPocket {
            pocket: Pocket::new("circle", circle(l)),
            width: l,
        },
        BenchPocket {
            pocket: Pocket::new("rounded-square", rounded_rect(l, l, 0.15 * l)),
            width: l,
        },
        BenchPocket {
            pocket: Pocket::new("pentagon", rounded_ngon(5, pent_rho, 0.2 * pent_rho)),
            width: 2.0 * pent_rho * 36f64.to_radians().cos(),
        },
        BenchPocket {
            pocket: Pocket::new("isogrid-triangle", rounded_ngon(3, tri_rho, 0.12 * l)),
            width: l / 3f64.sqrt(),
        },
        BenchPocket {
            pocket: Pocket::new("slot", rounded_rect(l, l / 4.0, 0.3 * l / 4.0)),
            width: l / 4.0,
        },
    ]
}

/// FreeCAD Adaptive peer: `python script in.json out.json` (see `tools/peers/freecad/`).
#[derive(Debug, Clone)]
pub struct AdaptivePeer {
    pub python: String,
    pub script: PathBuf,
}

impl AdaptivePeer {
    /// The peer in this checkout if `tools/peers/freecad/setup.sh` has been run (the unpacked
    /// FreeCAD library exists), else `None`.
    pub fn detect() -> Option<AdaptivePeer> {
        let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../tools/peers/freecad");
        let script = root.join("adaptive_pocket.py");
        let home = std::env::var_os("HOME")?;
        let lib =
            PathBuf::from(home).join(".cache/thinplan-freecad/usr/lib/freecad-python3/lib/area.so");
        if script.exists() && lib.exists() {
            Some(AdaptivePeer {
                python: "python3".into(),
                script,
            })
        } else {
            None
        }
    }

    /// Run FreeCAD's Adaptive2d on the pocket; the tool-centre path as one polyline.
    pub fn run(&self, pocket: &Pocket, params: &PocketParams) -> Result<Vec<DVec2>, String> {
        self.run_path(pocket, params).map(|p| p.points)
    }

    /// Run FreeCAD's Adaptive2d on the pocket: the tool-centre path as one polyline and the
    /// helix it enters by.
    pub fn run_path(&self, pocket: &Pocket, params: &PocketParams) -> Result<AdaptivePath, String> {
        let size = pocket.size();
        let pts = sample_pline(&pocket.outer, size / 400.0, 2f64.to_radians());
        let input = serde_json::json!({
            "outer": pts.iter().map(|p| [p.x, p.y]).collect::<Vec<_>>(),
            "tool_diameter": params.tool_diameter,
            "stepover": params.stepover,
            "finish_stepover": params.finish_stepover,
        });
        let dir = std::env::temp_dir().join(format!(
            "thinplan-adaptive-{}-{}",
            std::process::id(),
            pocket.name
        ));
        std::fs::create_dir_all(&dir).map_err(|e| e.to_string())?;
        let inp = dir.join("in.json");
        let outp = dir.join("out.json");
        std::fs::write(&inp, input.to_string()).map_err(|e| e.to_string())?;
        let st = std::process::Command::new(&self.python)
            .arg(&self.script)
            .arg(&inp)
            .arg(&outp)
            .output()
            .map_err(|e| e.to_string())?;
        if !st.status.success() {
            return Err(String::from_utf8_lossy(&st.stderr).into_owned());
        }
        let text = std::fs::read_to_string(&outp).map_err(|e| e.to_string())?;
        let _ = std::fs::remove_dir_all(&dir);
        let v: serde_json::Value = serde_json::from_str(&text).map_err(|e| e.to_string())?;
        let pts = v["points"]
            .as_array()
            .ok_or("no points in FreeCAD output")?
            .iter()
            .filter_map(|p| Some(DVec2::new(p[0].as_f64()?, p[1].as_f64()?)))
            .collect::<Vec<_>>();
        if pts.len() < 2 {
            return Err("FreeCAD Adaptive returned no path".into());
        }
        // FreeCAD enters each region by a helix about HelixCenterPoint through StartPoint
        // (PathAdaptive.py: radius = their distance); the helix is not in `points`
        let helix = match (v["helix_center"].as_array(), v["helix_radius"].as_f64()) {
            (Some(c), Some(r)) => c[0]
                .as_f64()
                .zip(c[1].as_f64())
                .map(|(x, y)| (DVec2::new(x, y), r)),
            _ => None,
        };
        let lifted_moves = v["motion_types"]
            .as_array()
            .is_some_and(|t| t.iter().any(|m| m.as_i64() == Some(2)));
        let regions = v["regions"].as_u64().unwrap_or(1) as usize;
        Ok(AdaptivePath {
            points: pts,
            helix,
            regions,
            lifted_moves,
        })
    }
}

/// FreeCAD Adaptive's output.
#[derive(Debug, Clone)]
pub struct AdaptivePath {
    /// Tool-centre path, every move in order.
    pub points: Vec<DVec2>,
    /// Entry helix of the first region (centre, tool-centre radius); `None` from an older
    /// script.
    pub helix: Option<(DVec2, f64)>,
    /// Cleared regions (each entered by its own helix).
    pub regions: usize,
    /// Whether the path has "link not clear" moves (lifted over uncut stock in FreeCAD; the
    /// bench replays them at cutting depth).
    pub lifted_moves: bool,
}

impl AdaptivePath {
    /// The material cleared by the entry, for the engagement measure.
    pub fn entry(&self) -> Entry {
        match self.helix {
            Some((center, radius)) => Entry::Helix { center, radius },
            None => Entry::Plunge,
        }
    }
}

/// TOPP-RA's time of one path (s) and its curve (the spline through the path's points) sampled
/// for our schedule.
pub type ToppraTime = (f64, Vec<DVec2>);

/// TOPP-RA peer (`tools/peers/toppra/`): the venv's python and `toppra_time.py`.
#[derive(Debug, Clone)]
pub struct ToppraPeer {
    pub python: PathBuf,
    pub script: PathBuf,
}

impl ToppraPeer {
    /// The peer if `tools/peers/toppra/setup.sh` has been run (the venv at `$THINPLAN_VENV` or
    /// `$HOME/.cache/thinplan-venv` has a python with toppra), else `None`.
    pub fn detect() -> Option<ToppraPeer> {
        let script = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
            .join("../../tools/peers/toppra/toppra_time.py");
        let venv = std::env::var_os("THINPLAN_VENV")
            .map(PathBuf::from)
            .or_else(|| {
                std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".cache/thinplan-venv"))
            })?;
        let python = venv.join("bin/python");
        let has_toppra = std::fs::read_dir(venv.join("lib"))
            .ok()?
            .filter_map(|e| e.ok())
            .any(|e| e.path().join("site-packages/toppra").exists());
        (script.exists() && python.exists() && has_toppra).then_some(ToppraPeer { python, script })
    }

    /// The limits both sides use for the ratio: the machine's per-axis limits only (TOPP-RA has
    /// no centripetal cap, no feed cap and no corner stops).
    pub fn limits(machine: &MachineLimits) -> MachineLimits {
        MachineLimits {
            a_centripetal: f64::INFINITY,
            ..machine.clone()
        }
    }

    /// TOPP-RA times (s) of several planar paths in one run of the script, each with the
    /// script's cubic spline through the points sampled at [`Self::RESAMPLE`] points per
    /// segment (so that our schedule can time the same curve); `None` where TOPP-RA failed.
    pub fn times(
        &self,
        paths: &[(String, Vec<DVec2>)],
        limits: &MachineLimits,
    ) -> Result<Vec<Option<ToppraTime>>, String> {
        let input = serde_json::json!({
            "paths": paths.iter().map(|(name, pts)| serde_json::json!({
                "name": name,
                "points": pts.iter().map(|p| [p.x, p.y]).collect::<Vec<_>>(),
                "v_max": limits.v_max,
                "a_max": limits.a_max,
            })).collect::<Vec<_>>()
        });
        let dir = std::env::temp_dir().join(format!("thinplan-toppra-{}", std::process::id()));
        std::fs::create_dir_all(&dir).map_err(|e| e.to_string())?;
        let inp = dir.join("paths.json");
        std::fs::write(&inp, input.to_string()).map_err(|e| e.to_string())?;
        let out = std::process::Command::new(&self.python)
            .arg(&self.script)
            .arg(&inp)
            .args(["--grid-factor", &Self::GRID_FACTOR.to_string()])
            .args(["--min-grid", "2000"])
            .args(["--resample", &Self::RESAMPLE.to_string()])
            .output()
            .map_err(|e| e.to_string())?;
        let _ = std::fs::remove_dir_all(&dir);
        if !out.status.success() {
            return Err(String::from_utf8_lossy(&out.stderr).into_owned());
        }
        let v: serde_json::Value =
            serde_json::from_slice(&out.stdout).map_err(|e| e.to_string())?;
        let res = v["results"]
            .as_array()
            .ok_or("no results from toppra_time.py")?;
        Ok(res
            .iter()
            .map(|r| {
                let t = r["time"].as_f64().filter(|t| *t > 0.0)?;
                let pts = r["resampled"]
                    .as_array()?
                    .iter()
                    .map(|p| Some(DVec2::new(p[0].as_f64()?, p[1].as_f64()?)))
                    .collect::<Option<Vec<_>>>()?;
                Some((t, pts))
            })
            .collect())
    }

    /// Spline samples per input segment for our side of the same-curve comparison.
    pub const RESAMPLE: usize = 32;
    /// TOPP-RA gridpoints per input point (half a gridpoint per resampled point: collocation
    /// on a coarser grid is optimistic, so the ratio errs against us).
    pub const GRID_FACTOR: usize = 16;
}

/// A path cut at its corner stops (junctions turning more than `corner_deg`, where our
/// schedule stops and TOPP-RA, which has no corners, would not): the pieces between them,
/// repeated points dropped. Each piece is timed rest to rest by both sides and the times
/// summed, which for our schedule equals the time of the whole path.
pub fn toppra_pieces(points: &[DVec2], corner_deg: f64) -> Vec<Vec<DVec2>> {
    let cos_lim = corner_deg.to_radians().cos();
    let mut pieces: Vec<Vec<DVec2>> = Vec::new();
    let mut cur: Vec<DVec2> = Vec::new();
    for &p in points {
        if cur.last().is_some_and(|q| q.distance_squared(p) < 1e-18) {
            continue;
        }
        if cur.len() >= 2 {
            let a = (cur[cur.len() - 1] - cur[cur.len() - 2]).normalize();
            let b = (p - cur[cur.len() - 1]).normalize();
            if a.dot(b) < cos_lim {
                let q = cur[cur.len() - 1];
                pieces.push(std::mem::replace(&mut cur, vec![q]));
            }
        }
        cur.push(p);
    }
    if cur.len() >= 2 {
        pieces.push(cur);
    }
    pieces
}

/// Our time over TOPP-RA's under the same limits, piece by piece between corner stops.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct ToppraRatios {
    /// Same curve on both sides: TOPP-RA's cubic spline through our points, which our
    /// schedule times sampled at [`ToppraPeer::RESAMPLE`] points per segment.
    pub same_curve: f64,
    /// Our schedule on our own points (the time the bench reports) over TOPP-RA on the spline
    /// through them: differs by the schedule's discretisation and by the geometry (polyline
    /// with three-point curvature vs spline).
    pub native: f64,
}

/// TOPP-RA ratios of several paths (one script run); `None` for a path where TOPP-RA failed
/// on a piece. Pieces of two points are straight lines, timed exactly by both: ours counts
/// for both.
pub fn toppra_ratios(
    peer: &ToppraPeer,
    paths: &[Vec<DVec2>],
    limits: &MachineLimits,
) -> Result<Vec<Option<ToppraRatios>>, String> {
    let mut jobs: Vec<(String, Vec<DVec2>)> = Vec::new();
    let mut owner: Vec<usize> = Vec::new();
    // per path: ours on the same curve, ours native, TOPP-RA, every piece solved
    let mut sums = vec![(0.0, 0.0, 0.0, true); paths.len()];
    for (k, path) in paths.iter().enumerate() {
        for piece in toppra_pieces(path, limits.corner_angle_deg) {
            let ours = time_path(&piece, 1e6, limits).total_time;
            let s = &mut sums[k];
            s.1 += ours;
            if piece.len() < 3 {
                s.0 += ours;
                s.2 += ours;
            } else {
                jobs.push((format!("path {k} piece {}", jobs.len()), piece));
                owner.push(k);
            }
        }
    }
    if !jobs.is_empty() {
        for (k, res) in owner.iter().zip(peer.times(&jobs, limits)?) {
            let s = &mut sums[*k];
            match res {
                Some((t, pts)) => {
                    s.0 += time_path(&pts, 1e6, limits).total_time;
                    s.2 += t;
                }
                None => s.3 = false,
            }
        }
    }
    Ok(sums
        .into_iter()
        .map(|(same, native, theirs, ok)| {
            (ok && theirs > 0.0).then(|| ToppraRatios {
                same_curve: same / theirs,
                native: native / theirs,
            })
        })
        .collect())
}

/// The scales stage 7 tries the helix radius at, largest first (`operations::layers::enter`).
pub const HELIX_SCALES: [f64; 3] = [1.0, 0.5, 0.25];

/// How the planner enters a spiral's first block (stage 7, `operations::layers::enter`): a
/// helix of radius ρ = `radius` × D × scale ending at the path's first point p0, centred at
/// p0 − (ρ, 0), for the first scale in [`HELIX_SCALES`] at which the circle fits in the
/// tool-centre region; a plunge (a ramp in the planner) where none fits.
#[derive(Debug, Clone, PartialEq)]
pub struct HelixEntryRule {
    /// Helix radius (tool-centre path), fraction of D.
    pub radius: f64,
    /// Where `radius` was read (provenance).
    pub source: String,
}

/// How a path entered the stock: what the engagement measure clears first, and its label for
/// the JSON rows (`"plunge"`, `"helix r=0.40D"`).
#[derive(Debug, Clone, PartialEq)]
pub struct PathEntry {
    pub entry: Entry,
    pub label: String,
}

impl PathEntry {
    pub fn plunge() -> Self {
        PathEntry {
            entry: Entry::Plunge,
            label: "plunge".into(),
        }
    }
}

impl HelixEntryRule {
    /// The helix of the built-in knowledge's closed-pocket method (`knowledge/methods.ron`);
    /// `None` when that method enters by a ramp (or the built-in knowledge does not load).
    pub fn builtin() -> Option<Self> {
        let k = thinplan_knowledge::Knowledge::builtin().ok()?;
        // a closed pocket: every side is product; the bench's floors are not
        let m = k
            .methods
            .for_feature(false, thinplan_knowledge::SidesMatch::Closed)?;
        match m.entry {
            thinplan_knowledge::LevelEntry::Helix { radius, .. } => Some(HelixEntryRule {
                radius,
                source: format!("builtin:knowledge/methods.ron, method `{}`", m.id),
            }),
            thinplan_knowledge::LevelEntry::Ramp { .. } => None,
        }
    }

    /// Stage 7's entry for a path that starts at `p0` in the tool-centre region bounded by the
    /// closed loop `boundary` (∂Ω), tool diameter `tool`: the helix at the first scale whose
    /// centre lies inside ∂Ω at least ρ from it, else a plunge.
    pub fn entry(&self, p0: DVec2, boundary: &[DVec2], tool: f64) -> PathEntry {
        if boundary.len() < 3 || !(self.radius.is_finite() && self.radius > 0.0) {
            return PathEntry::plunge();
        }
        let idx = SegIndex::new(&[boundary], true);
        for s in HELIX_SCALES {
            let rho = self.radius * tool * s;
            let c = p0 - DVec2::new(rho, 0.0);
            // the same margin as stage 7
            if point_in_loop(c, boundary) && idx.nearest(c) >= rho + 1e-6 {
                return PathEntry {
                    entry: Entry::Helix {
                        center: c,
                        radius: rho,
                    },
                    label: format!("helix r={:.2}D", self.radius * s),
                };
            }
        }
        PathEntry {
            entry: Entry::Plunge,
            label: "plunge (no helix fits)".into(),
        }
    }
}

/// Benchmark configuration.
#[derive(Debug, Clone)]
pub struct BenchConfig {
    pub limits: MachineLimits,
    /// Cutting feed cap (mm/s); `None` = the machine's X/Y velocity limit (Bieterman's setting:
    /// the feed is limited by the axis drives only).
    pub feed: Option<f64>,
    /// Pocket sizes as multiples of D = V²/(2A).
    pub l_over_d: Vec<f64>,
    /// Which pockets (by name); empty = all.
    pub pockets: Vec<String>,
    /// FreeCAD Adaptive peer, if available.
    pub adaptive: Option<AdaptivePeer>,
    /// Run FreeCAD Adaptive only up to this L/D (it takes minutes per pocket at 40 and 100);
    /// `adaptive` is null above it.
    pub adaptive_max_l_over_d: f64,
    /// TOPP-RA peer, if available (fills `toppra_ratio`).
    pub toppra: Option<ToppraPeer>,
    /// Field and distance blend of the curvilinear paths (see [`PocketParams`]).
    pub field: crate::Field,
    pub distance_blend: f64,
    /// Measure the engagement of every path ([`crate::engagement`]); `None` = skip (the
    /// engagement fields are then null).
    pub engagement: Option<EngagementParams>,
    /// How the curvilinear path (whichever spiral was kept) enters, for the engagement measure:
    /// stage 7's helix ([`HelixEntryRule::builtin`]); `None` = a plunge at its first point. The
    /// offset baselines always plunge.
    pub helix_entry: Option<HelixEntryRule>,
    /// Also measure the curvilinear path with a plunge (fills `curvilinear.plunge`) and with a
    /// helix about its centre, started where it leaves the helix circle (fills
    /// `curvilinear.centred_helix`), to compare the entries on the same spiral.
    pub compare_entries: bool,
}

impl Default for BenchConfig {
    fn default() -> Self {
        BenchConfig {
            limits: MachineLimits::typical_hsm(),
            feed: None,
            l_over_d: vec![0.5, 1.0, 2.0, 4.0, 10.0],
            pockets: Vec::new(),
            adaptive: AdaptivePeer::detect(),
            adaptive_max_l_over_d: f64::INFINITY,
            toppra: ToppraPeer::detect(),
            field: crate::Field::Poisson,
            distance_blend: 0.0,
            engagement: Some(EngagementParams::default()),
            helix_entry: HelixEntryRule::builtin(),
            compare_entries: false,
        }
    }
}

impl BenchConfig {
    /// The set `thinplan bench pockets` runs: every bench pocket at L/D = 0.5, 1, 2, 4, 10,
    /// 20, 40, 100 (Bieterman's range), FreeCAD Adaptive up to L/D 10 (it takes minutes per
    /// pocket at 40 and 100; null above).
    pub fn cli() -> Self {
        BenchConfig {
            l_over_d: vec![0.5, 1.0, 2.0, 4.0, 10.0, 20.0, 40.0, 100.0],
            adaptive_max_l_over_d: 10.0,
            ..BenchConfig::default()
        }
    }
}

/// Length and time of one path.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct PathStats {
    pub length_mm: f64,
    pub time_s: f64,
    /// Max measured gap between successive orbits (mm); null for peers.
    pub max_gap_mm: Option<f64>,
    /// Engagement measured on the material ([`crate::engagement`]): max and 99th percentile
    /// engagement angle (degrees), max radial engagement (mm); null when not measured.
    #[serde(default)]
    pub max_engagement_deg: Option<f64>,
    #[serde(default)]
    pub p99_engagement_deg: Option<f64>,
    #[serde(default)]
    pub max_radial_mm: Option<f64>,
    /// The entry the engagement was measured with ([`PathEntry::label`]); null in older JSON.
    #[serde(default)]
    pub entry: Option<String>,
}

impl PathStats {
    fn new(
        t: &crate::timing::Schedule,
        max_gap: Option<f64>,
        e: Option<EngagementStats>,
        entry: &str,
    ) -> Self {
        PathStats {
            length_mm: t.length,
            time_s: t.total_time,
            max_gap_mm: max_gap,
            max_engagement_deg: e.map(|e| e.max_engagement_deg),
            p99_engagement_deg: e.map(|e| e.p99_engagement_deg),
            max_radial_mm: e.map(|e| e.max_radial_mm),
            entry: Some(entry.to_string()),
        }
    }
}

/// The curvilinear path's stats and the method actually used.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct CurvilinearStats {
    pub length_mm: f64,
    pub time_s: f64,
    pub max_gap_mm: f64,
    /// "curvilinear", "offset-spiral" or "offset-fallback".
    pub method: String,
    /// Why: which spiral was kept over the other, or why it fell back to offsets
    /// ([`crate::PocketPath::choice`] / `fallback_reason`).
    #[serde(default)]
    pub choice: Option<String>,
    /// As in [`PathStats`].
    #[serde(default)]
    pub max_engagement_deg: Option<f64>,
    #[serde(default)]
    pub p99_engagement_deg: Option<f64>,
    #[serde(default)]
    pub max_radial_mm: Option<f64>,
    /// The entry the engagement was measured with: stage 7's helix (`"helix r=0.40D"`) or
    /// `"plunge"`; null in older JSON (measured with a plunge).
    #[serde(default)]
    pub entry: Option<String>,
    /// The same path measured with a plunge at its first point
    /// ([`BenchConfig::compare_entries`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub plunge: Option<EngagementStats>,
    /// The path entered by a helix about its centre (same radius rule) and started where it
    /// leaves the helix circle ([`crate::PocketPath::after_centred_helix`];
    /// [`BenchConfig::compare_entries`]): its own length, time and engagement.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub centred_helix: Option<PathStats>,
}

/// One benchmark row.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct BenchRow {
    pub pocket: String,
    pub l_over_d: f64,
    /// L (mm): largest bounding-box side.
    pub size_mm: f64,
    pub stepover_mm: f64,
    pub tool_mm: f64,
    pub offset: PathStats,
    pub curvilinear: CurvilinearStats,
    pub adaptive: Option<PathStats>,
    /// Time saving of curvilinear vs offset, % of the offset time.
    pub saving_pct: f64,
    /// Conventional "rectilinear" baseline: the same offset rings with convex arcs replaced by
    /// chords (sharp corners, a stop at each), links as in `offset` ([`offset_path_sharp`]).
    pub offset_sharp: PathStats,
    /// Time saving of curvilinear vs `offset_sharp`, %.
    pub saving_vs_sharp_pct: f64,
    /// Offset rings held to the spiral's maximum engagement: ring stepover reduced until the
    /// measured ring gap ≤ `stepover_mm` ([`offset_path_gap_matched`]).
    pub offset_gap_matched: PathStats,
    /// The ring stepover that needed (mm).
    pub gap_matched_ring_step_mm: f64,
    /// Time saving of curvilinear vs `offset_gap_matched`, %.
    pub saving_vs_gap_matched_pct: f64,
    /// Roughing orbits of the spiral (turns about the centre, without the finishing pass) and
    /// offset rings (without the finishing ring).
    pub curvilinear_turns: usize,
    pub offset_rings: usize,
    /// Lower bound on the spiral's turns for any orbit spacing with gap ≤ stepover and the
    /// same first turn ([`crate::PocketPath::turns_lower_bound`]); null for a fallback.
    pub curvilinear_turns_bound: Option<usize>,
    /// Our schedule's time over TOPP-RA's on the whole curvilinear path, the same curve on
    /// both sides, piece by piece between corner stops ([`toppra_ratios`]); null without the
    /// peer.
    pub toppra_ratio: Option<f64>,
    /// The same with our schedule on the path's own points ([`ToppraRatios::native`]).
    pub toppra_ratio_native: Option<f64>,
    /// Rectilinear (zigzag) baseline, the one Bieterman's time-saving chart compares against
    /// ([`best_zigzag`]: passes ≤ stepover apart joined along the roughing boundary, then
    /// the same finishing pass, at the pass angle of least time); null in older JSON or where
    /// the pocket takes no zigzag.
    #[serde(default)]
    pub zigzag: Option<PathStats>,
    /// The pass angle used (degrees from +x).
    #[serde(default)]
    pub zigzag_angle_deg: Option<f64>,
    /// Time saving of curvilinear vs `zigzag`, %.
    #[serde(default)]
    pub saving_vs_zigzag_pct: Option<f64>,
}

/// Pass angles [`best_zigzag`] tries (degrees): every 15°.
pub const ZIGZAG_ANGLES_DEG: [f64; 12] = [
    0.0, 15.0, 30.0, 45.0, 60.0, 75.0, 90.0, 105.0, 120.0, 135.0, 150.0, 165.0,
];

/// The zigzag baseline at its best: of the pass angles in [`ZIGZAG_ANGLES_DEG`], the one whose
/// path our schedule times fastest (ties: the first). Returns the path, its schedule and the
/// angle in degrees; `None` if no angle gives a zigzag (islands, a pass meeting the boundary
/// more than twice).
pub fn best_zigzag(
    pocket: &Pocket,
    params: &PocketParams,
    feed: f64,
    limits: &MachineLimits,
) -> Option<(PocketPath, crate::timing::Schedule, f64)> {
    let mut best: Option<(PocketPath, crate::timing::Schedule, f64)> = None;
    for deg in ZIGZAG_ANGLES_DEG {
        let Ok(p) = zigzag_path(pocket, params, deg.to_radians()) else {
            continue;
        };
        let t = time_path(&p.points, feed, limits);
        if best.as_ref().is_none_or(|b| t.total_time < b.1.total_time) {
            best = Some((p, t, deg));
        }
    }
    best
}

/// Parameters used for a bench pocket: tool = width / 6, stepover 40 % and finishing 10 % of
/// the tool (so every size has the same geometry in tool units; only L/D changes).
pub fn bench_params(bp: &BenchPocket) -> PocketParams {
    PocketParams::for_tool(bp.width / 6.0)
}

/// Time offset, curvilinear and (if available) FreeCAD Adaptive paths over the bench family.
pub fn bench_pockets(cfg: &BenchConfig) -> Result<Vec<BenchRow>, PocketError> {
    let d = cfg.limits.accel_distance();
    let feed = cfg
        .feed
        .unwrap_or(cfg.limits.v_max[0].min(cfg.limits.v_max[1]));
    let mut rows = Vec::new();
    let tlim = ToppraPeer::limits(&cfg.limits);
    let mut topp: Vec<(usize, Vec<DVec2>)> = Vec::new();
    for &ld in &cfg.l_over_d {
        let l = ld * d;
        for bp in bench_family(l) {
            if !cfg.pockets.is_empty() && !cfg.pockets.contains(&bp.pocket.name) {
                continue;
            }
            let mut params = bench_params(&bp);
            params.field = cfg.field;
            params.distance_blend = cfg.distance_blend;
            let off = offset_path(&bp.pocket, &params)?;
            let cur = curvilinear_path(&bp.pocket, &params)?;
            let sharp = offset_path_sharp(&bp.pocket, &params)?;
            let (matched, matched_step) = offset_path_gap_matched(&bp.pocket, &params)?;
            let t_off = time_path(&off.points, feed, &cfg.limits);
            let t_cur = time_path(&cur.points, feed, &cfg.limits);
            let t_sharp = time_path(&sharp.points, feed, &cfg.limits);
            let t_matched = time_path(&matched.points, feed, &cfg.limits);
            let tool = params.tool_diameter;
            let eng = |pts: &[DVec2], entry: Entry| {
                cfg.engagement
                    .as_ref()
                    .and_then(|ep| engagement_stats(pts, tool, entry, ep))
            };
            // the offset baselines plunge at their first point
            let stats = |t: &crate::timing::Schedule, p: &crate::PocketPath| {
                PathStats::new(t, Some(p.max_gap), eng(&p.points, Entry::Plunge), "plunge")
            };
            // the spiral enters as stage 7 would enter it
            let cur_entry = match (&cfg.helix_entry, cur.points.first()) {
                (Some(rule), Some(&p0)) => rule.entry(p0, &cur.boundary, tool),
                _ => PathEntry::plunge(),
            };
            let e_cur = eng(&cur.points, cur_entry.entry);
            let e_cur_plunge = if cfg.compare_entries {
                eng(&cur.points, Entry::Plunge)
            } else {
                None
            };
            let centred = match (&cfg.helix_entry, cfg.compare_entries) {
                (Some(rule), true) => {
                    let radii = HELIX_SCALES.map(|s| rule.radius * tool * s);
                    cur.after_centred_helix(&radii).map(|(p, h)| {
                        let t = time_path(&p.points, feed, &cfg.limits);
                        let entry = Entry::Helix {
                            center: h.center,
                            radius: h.radius,
                        };
                        let label = format!("centred helix r={:.2}D", h.radius / tool);
                        PathStats::new(&t, Some(p.max_gap), eng(&p.points, entry), &label)
                    })
                }
                _ => None,
            };
            let adaptive = cfg
                .adaptive
                .as_ref()
                .filter(|_| ld <= cfg.adaptive_max_l_over_d);
            let adaptive = adaptive.and_then(|peer| {
                peer.run_path(&bp.pocket, &params).ok().map(|ap| {
                    if ap.regions != 1 || ap.lifted_moves {
                        eprintln!(
                            "note: FreeCAD Adaptive on {} (L/D {ld}): {} regions{}; engagement \
                             counts only the first region's helix",
                            bp.pocket.name,
                            ap.regions,
                            if ap.lifted_moves {
                                ", lifted links replayed at depth"
                            } else {
                                ""
                            }
                        );
                    }
                    let t = time_path(&ap.points, feed, &cfg.limits);
                    let entry = match ap.helix {
                        Some((_, r)) => format!("helix r={:.2}D", r / tool),
                        None => "plunge".into(),
                    };
                    PathStats::new(&t, None, eng(&ap.points, ap.entry()), &entry)
                })
            });
            let zz = best_zigzag(&bp.pocket, &params, feed, &cfg.limits);
            if cfg.toppra.is_some() {
                topp.push((rows.len(), cur.points.clone()));
            }
            rows.push(BenchRow {
                pocket: bp.pocket.name.clone(),
                l_over_d: ld,
                size_mm: l,
                stepover_mm: params.stepover,
                tool_mm: params.tool_diameter,
                offset: stats(&t_off, &off),
                curvilinear: CurvilinearStats {
                    length_mm: t_cur.length,
                    time_s: t_cur.total_time,
                    max_gap_mm: cur.max_gap,
                    method: cur.method.as_str().into(),
                    choice: cur.choice.clone().or(cur.fallback_reason.clone()),
                    max_engagement_deg: e_cur.map(|e| e.max_engagement_deg),
                    p99_engagement_deg: e_cur.map(|e| e.p99_engagement_deg),
                    max_radial_mm: e_cur.map(|e| e.max_radial_mm),
                    entry: Some(cur_entry.label.clone()),
                    plunge: e_cur_plunge,
                    centred_helix: centred,
                },
                adaptive,
                saving_pct: 100.0 * (1.0 - t_cur.total_time / t_off.total_time),
                offset_sharp: stats(&t_sharp, &sharp),
                saving_vs_sharp_pct: 100.0 * (1.0 - t_cur.total_time / t_sharp.total_time),
                offset_gap_matched: stats(&t_matched, &matched),
                gap_matched_ring_step_mm: matched_step,
                saving_vs_gap_matched_pct: 100.0 * (1.0 - t_cur.total_time / t_matched.total_time),
                curvilinear_turns: cur.roughing_turns(),
                offset_rings: off.contours.len().saturating_sub(1),
                curvilinear_turns_bound: cur.turns_lower_bound(params.stepover),
                toppra_ratio: None,
                toppra_ratio_native: None,
                saving_vs_zigzag_pct: zz
                    .as_ref()
                    .map(|(_, t, _)| 100.0 * (1.0 - t_cur.total_time / t.total_time)),
                zigzag_angle_deg: zz.as_ref().map(|z| z.2),
                zigzag: zz.map(|(p, t, _)| stats(&t, &p)),
            });
        }
    }
    if let (Some(peer), false) = (&cfg.toppra, topp.is_empty()) {
        let paths: Vec<Vec<DVec2>> = topp.iter().map(|(_, p)| p.clone()).collect();
        match toppra_ratios(peer, &paths, &tlim) {
            Ok(ratios) => {
                for ((row, _), r) in topp.iter().zip(ratios) {
                    rows[*row].toppra_ratio = r.map(|r| r.same_curve);
                    rows[*row].toppra_ratio_native = r.map(|r| r.native);
                }
            }
            Err(e) => eprintln!("TOPP-RA peer failed: {e}"),
        }
    }
    Ok(rows)
}

/// The rows as a fixed-width text table. `save %` columns: curvilinear time saving over the
/// arc offset baseline (`offset`), the sharp-cornered one (`sharp`) and the gap-matched one
/// (`gapm`, ring stepover `s'`); `turns/bd/rings`: spiral turns, their lower bound, offset rings;
/// `eng p99°`: 99th-percentile engagement angle of offset / curvilinear / gap-matched / Adaptive
/// paths (their max is in the JSON; the curvilinear path is measured with stage 7's helix entry,
/// the offset baselines with a plunge, whose first move is a 180° slot).
pub fn format_table(rows: &[BenchRow]) -> String {
    use std::fmt::Write;
    let mut s = String::new();
    let _ = writeln!(
        s,
        "{:<17} {:>5} {:>6} {:>5} {:>5} | {:>6} {:>6} | {:>7} {:>6} {:>11} | {:>6} {:>6} | {:>6} | {:>5} {:>7} {:>6} | {:>6} {:>6} {:>4} | {:>6} {:>6} {:>6} {:>6} | {:>10} | {:>13} | {:>19}",
        "pocket", "L/D", "L mm", "tool", "step", "off mm", "off s", "curv mm", "curv s", "method",
        "adp mm", "adp s", "shrp s", "s'", "gapm mm", "gapm s", "zz mm", "zz s", "zz°", "save%",
        "sharp", "gapm", "zz", "turns/bd/r", "TOPP-RA s/n", "eng p99° o/c/g/a"
    );
    for r in rows {
        let (am, at) = match &r.adaptive {
            Some(a) => (format!("{:.0}", a.length_mm), format!("{:.2}", a.time_s)),
            None => ("-".into(), "-".into()),
        };
        let method = match r.curvilinear.method.as_str() {
            "offset-fallback" => "fallback",
            m => m,
        };
        let turns = format!(
            "{}/{}/{}",
            r.curvilinear_turns,
            r.curvilinear_turns_bound
                .map(|b| b.to_string())
                .unwrap_or_else(|| "-".into()),
            r.offset_rings
        );
        let (zm, zt, za, zs) = match (&r.zigzag, r.zigzag_angle_deg, r.saving_vs_zigzag_pct) {
            (Some(z), Some(a), Some(p)) => (
                format!("{:.0}", z.length_mm),
                format!("{:.2}", z.time_s),
                format!("{a:.0}"),
                format!("{p:.1}"),
            ),
            _ => ("-".into(), "-".into(), "-".into(), "-".into()),
        };
        let _ = writeln!(
            s,
            "{:<17} {:>5.1} {:>6.1} {:>5.2} {:>5.2} | {:>6.0} {:>6.2} | {:>7.0} {:>6.2} {:>11} | {:>6} {:>6} | {:>6.2} | {:>5.2} {:>7.0} {:>6.2} | {:>6} {:>6} {:>4} | {:>6.1} {:>6.1} {:>6.1} {:>6} | {:>10} | {:>13} | {:>19}",
            r.pocket,
            r.l_over_d,
            r.size_mm,
            r.tool_mm,
            r.stepover_mm,
            r.offset.length_mm,
            r.offset.time_s,
            r.curvilinear.length_mm,
            r.curvilinear.time_s,
            method,
            am,
            at,
            r.offset_sharp.time_s,
            r.gap_matched_ring_step_mm,
            r.offset_gap_matched.length_mm,
            r.offset_gap_matched.time_s,
            zm,
            zt,
            za,
            r.saving_pct,
            r.saving_vs_sharp_pct,
            r.saving_vs_gap_matched_pct,
            zs,
            turns,
            match (r.toppra_ratio, r.toppra_ratio_native) {
                (Some(a), Some(b)) => format!("{a:.4}/{b:.4}"),
                _ => "-".into(),
            },
            [
                r.offset.p99_engagement_deg,
                r.curvilinear.p99_engagement_deg,
                r.offset_gap_matched.p99_engagement_deg,
                r.adaptive.as_ref().and_then(|a| a.p99_engagement_deg),
            ]
            .iter()
            .map(|e| e.map_or("-".into(), |e| format!("{e:.0}")))
            .collect::<Vec<String>>()
            .join("/")
        );
    }
    s
}
