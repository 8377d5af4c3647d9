//! Machines, tools and materials: the resources a set-up names.

use serde::{Deserialize, Serialize};

use crate::at;
use crate::check::{Checks, Range, Seg};

/// The smallest and largest tool diameter accepted (mm). The lower bound
/// keeps the work of a stepover bounded: at the smallest stepover
/// (0.01 · D, `methods.ron`) a 1 m wide feature gets 1000 / 0.002 = 5·10⁵
/// passes.
pub const TOOL_DIAMETER: Range = Range::closed(0.2, 250.0);

/// Limits of one linear axis.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LinearAxis {
    /// Travel range in mm, `(min, max)`.
    pub travel: (f64, f64),
    /// Maximum velocity, mm/s.
    pub v_max: f64,
    /// Maximum acceleration, mm/s².
    pub a_max: f64,
}

/// Which tool directions the machine can reach, relative to its spindle
/// pointing down the table's z axis.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum Kinematics {
    /// Tool along +z only.
    ThreeAxis,
    /// Indexed rotary axes: the tool can be tilted by up to `max_tilt_deg`
    /// from +z between operations, not while cutting.
    ThreePlusTwo { max_tilt_deg: f64 },
    /// A continuous 5-axis head: tilt range from +z and full rotation.
    FiveAxisHead { max_tilt_deg: f64 },
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Machine {
    pub id: String,
    pub name: String,
    pub x: LinearAxis,
    pub y: LinearAxis,
    pub z: LinearAxis,
    pub kinematics: Kinematics,
    /// Largest acceleration normal to the path the machine should see, mm/s².
    pub a_centripetal: f64,
    pub spindle_max_rpm: f64,
    pub spindle_power_kw: f64,
}

impl Machine {
    /// Problems with the values (each at its place in the file).
    pub fn checks(&self, c: &mut Checks) {
        let p = format!("machine `{}`: ", self.id);
        if self.id.is_empty() {
            c.push(at!["id"], "a machine has an empty id".into());
        }
        for (axis, a) in [("x", &self.x), ("y", &self.y), ("z", &self.z)] {
            let (lo, hi) = a.travel;
            let travel = Range::closed(-1e5, 1e5);
            c.range(
                at![axis, "travel", 0],
                &p,
                &format!("{axis}.travel min"),
                lo,
                travel,
                " mm",
            );
            c.range(
                at![axis, "travel", 1],
                &p,
                &format!("{axis}.travel max"),
                hi,
                travel,
                " mm",
            );
            if lo.is_finite() && hi.is_finite() && lo >= hi {
                c.push(
                    at![axis, "travel"],
                    format!("{p}axis {axis}: travel ({lo}, {hi}) is empty"),
                );
            }
            // At least 1 mm/s: feeds are capped by v_max, and a cap below
            // 1 mm/min would print F0.
            c.range(
                at![axis, "v_max"],
                &p,
                &format!("{axis}.v_max"),
                a.v_max,
                Range::closed(1.0, 10_000.0),
                " mm/s",
            );
            c.range(
                at![axis, "a_max"],
                &p,
                &format!("{axis}.a_max"),
                a.a_max,
                Range::above(0.0, 200_000.0),
                " mm/s²",
            );
        }
        c.range(
            at!["a_centripetal"],
            &p,
            "a_centripetal",
            self.a_centripetal,
            Range::above(0.0, 200_000.0),
            " mm/s²",
        );
        c.range(
            at!["spindle_max_rpm"],
            &p,
            "spindle_max_rpm",
            self.spindle_max_rpm,
            Range::closed(100.0, 200_000.0),
            " rpm",
        );
        c.range(
            at!["spindle_power_kw"],
            &p,
            "spindle_power_kw",
            self.spindle_power_kw,
            Range::above(0.0, 1000.0),
            " kW",
        );
        match self.kinematics {
            Kinematics::ThreeAxis => {}
            Kinematics::ThreePlusTwo { max_tilt_deg }
            | Kinematics::FiveAxisHead { max_tilt_deg } => c.range(
                at!["kinematics", "max_tilt_deg"],
                &p,
                "max_tilt_deg",
                max_tilt_deg,
                Range::closed(0.0, 180.0),
                "°",
            ),
        }
    }

    /// Whether the machine can point its tool along `dir` (unit vector from
    /// tool tip towards the spindle, in machine coordinates).
    pub fn reaches(&self, dir: glam::DVec3) -> bool {
        let tilt = dir
            .normalize_or_zero()
            .z
            .clamp(-1.0, 1.0)
            .acos()
            .to_degrees();
        match self.kinematics {
            Kinematics::ThreeAxis => tilt < 1e-6,
            Kinematics::ThreePlusTwo { max_tilt_deg }
            | Kinematics::FiveAxisHead { max_tilt_deg } => tilt <= max_tilt_deg + 1e-9,
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum ToolKind {
    FlatEndMill,
    BullNoseEndMill,
    BallEndMill,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Tool {
    pub id: String,
    pub kind: ToolKind,
    pub diameter: f64,
    pub corner_radius: f64,
    pub flutes: u32,
    /// Length of the cutting edge, mm.
    pub flute_length: f64,
    /// Length from holder face to tool tip, mm.
    pub stickout: f64,
    pub shank_diameter: f64,
    pub holder_diameter: f64,
    pub holder_length: f64,
    /// Largest depth of cut in a full slot, as a fraction of the diameter.
    pub max_slot_depth_ratio: f64,
    /// A necked (long-reach) tool: the diameter of its neck, mm, smaller
    /// than the cutter and at most the shank. Absent: no neck (the shank
    /// follows the flutes). Written as a plain number (`neck_diameter: 5.6`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub neck_diameter: Option<f64>,
    /// With a neck: the length from the tip over which the tool is no wider
    /// than its cutter and neck (the neck ends here, the shank begins), mm;
    /// between `flute_length` and `stickout`. Given with `neck_diameter`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reach: Option<f64>,
}

impl Tool {
    /// The tool's outline from the tip up as steps `(top, radius)`: the
    /// radius holds from the previous step's top (0 for the first) up to
    /// `top`, heights measured along the axis from the tip, mm. The cutter
    /// up to the flute length, the neck up to the reach, the shank up to the
    /// stickout (the holder face), the holder up to its length above that.
    pub fn radius_profile(&self) -> Vec<(f64, f64)> {
        let mut out = vec![(self.flute_length, self.diameter / 2.0)];
        if let (Some(neck), Some(reach)) = (self.neck_diameter, self.reach) {
            if reach > self.flute_length {
                out.push((reach, neck / 2.0));
            }
        }
        let below = out.last().map_or(0.0, |s| s.0);
        if self.stickout > below {
            out.push((self.stickout, self.shank_diameter / 2.0));
        }
        out.push((
            self.stickout + self.holder_length,
            self.holder_diameter / 2.0,
        ));
        out
    }

    /// The tool's radius at `height` above its tip (mm): 0 below the tip,
    /// the holder's radius at and above the holder face (what is above the
    /// holder, the spindle, is not known here).
    pub fn radius_at(&self, height: f64) -> f64 {
        if height < 0.0 {
            return 0.0;
        }
        let profile = self.radius_profile();
        profile
            .iter()
            .find(|(top, _)| height < *top)
            .or(profile.last())
            .map_or(0.0, |s| s.1)
    }
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ToolSet {
    pub id: String,
    pub name: String,
    pub tools: Vec<Tool>,
}

impl ToolSet {
    /// Problems with the values (each at its place in the file).
    pub fn checks(&self, c: &mut Checks) {
        if self.id.is_empty() {
            c.push(at!["id"], "a tool set has an empty id".into());
        }
        if self.tools.is_empty() {
            c.push(
                at!["tools"],
                format!("tool set `{}`: has no tools", self.id),
            );
        }
        let mut seen = std::collections::BTreeSet::new();
        for (i, t) in self.tools.iter().enumerate() {
            let p = format!("tool `{}` in set `{}`: ", t.id, self.id);
            let at = |f: &'static str| at!["tools", i, f];
            if t.id.is_empty() {
                c.push(at("id"), format!("{p}empty id"));
            } else if !seen.insert(t.id.as_str()) {
                c.push(at("id"), format!("{p}duplicate tool id"));
            }
            let d = t.diameter;
            c.range(at("diameter"), &p, "diameter", d, TOOL_DIAMETER, " mm");
            let r = t.corner_radius;
            c.range(
                at("corner_radius"),
                &p,
                "corner_radius",
                r,
                Range::closed(0.0, d / 2.0),
                " mm (0 to half the diameter)",
            );
            if t.kind == ToolKind::BallEndMill && (r - d / 2.0).abs() > 1e-6 {
                c.push(
                    at("corner_radius"),
                    format!("{p}a BallEndMill's corner_radius {r} must be half its diameter {d}"),
                );
            }
            c.count(at("flutes"), &p, "flutes", t.flutes, 1, 16);
            let fl = t.flute_length;
            c.range(
                at("flute_length"),
                &p,
                "flute_length",
                fl,
                Range::closed(0.1, 500.0),
                " mm",
            );
            let lo = if fl.is_finite() { fl.max(0.1) } else { 0.1 };
            c.range(
                at("stickout"),
                &p,
                "stickout",
                t.stickout,
                Range::closed(lo, 1000.0),
                " mm (at least the flute length)",
            );
            c.range(
                at("shank_diameter"),
                &p,
                "shank_diameter",
                t.shank_diameter,
                Range::above(0.0, 250.0),
                " mm",
            );
            let lo = if t.shank_diameter.is_finite() {
                t.shank_diameter.max(0.0)
            } else {
                0.0
            };
            c.range(
                at("holder_diameter"),
                &p,
                "holder_diameter",
                t.holder_diameter,
                Range::closed(lo, 1000.0),
                " mm (at least the shank diameter)",
            );
            c.range(
                at("holder_length"),
                &p,
                "holder_length",
                t.holder_length,
                Range::above(0.0, 1000.0),
                " mm",
            );
            c.range(
                at("max_slot_depth_ratio"),
                &p,
                "max_slot_depth_ratio",
                t.max_slot_depth_ratio,
                Range::closed(0.01, 10.0),
                " (fraction of the diameter)",
            );
            match (t.neck_diameter, t.reach) {
                (None, None) => {}
                (Some(neck), Some(reach)) => {
                    let hi = d.min(t.shank_diameter);
                    c.range(
                        at("neck_diameter"),
                        &p,
                        "neck_diameter",
                        neck,
                        Range {
                            lo: 0.0,
                            lo_incl: false,
                            hi,
                            hi_incl: hi < d,
                        },
                        " mm (below the diameter, at most the shank)",
                    );
                    let lo = if fl.is_finite() { fl } else { 0.0 };
                    c.range(
                        at("reach"),
                        &p,
                        "reach",
                        reach,
                        Range::closed(lo, t.stickout),
                        " mm (from the flute length to the stickout)",
                    );
                }
                (Some(_), None) => c.push(
                    at("neck_diameter"),
                    format!("{p}a neck_diameter needs its reach (where the neck ends)"),
                ),
                (None, Some(_)) => {
                    c.push(at("reach"), format!("{p}a reach needs its neck_diameter"))
                }
            }
        }
    }

    /// The set's reach and shortest flute: (largest diameter, shortest flute
    /// length), or `None` for an empty set. Shank rules use the pair: a
    /// neighbour within the reach, higher than the shortest flute above a
    /// feature's bottom, may meet some tool's shank.
    pub fn reach_and_rise(&self) -> Option<(f64, f64)> {
        let d = self.tools.iter().map(|t| t.diameter).fold(0.0, f64::max);
        let flute = self
            .tools
            .iter()
            .map(|t| t.flute_length)
            .fold(f64::INFINITY, f64::min);
        (d > 0.0 && flute.is_finite()).then_some((d, flute))
    }
}

/// Cutting data for a material with one tool kind.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CuttingData {
    /// Cutting speed, m/min.
    pub cutting_speed: f64,
    /// Feed per tooth for roughing and finishing, mm.
    pub feed_per_tooth_roughing: f64,
    pub feed_per_tooth_finishing: f64,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Material {
    pub id: String,
    pub name: String,
    /// Young's modulus, N/mm² (MPa).
    pub youngs_modulus: f64,
    /// kg/m³
    pub density: f64,
    /// Yield strength, N/mm².
    pub yield_strength: f64,
    pub cutting: CuttingData,
}

impl Material {
    /// Problems with the values (each at its place in the file).
    pub fn checks(&self, c: &mut Checks) {
        let p = format!("material `{}`: ", self.id);
        if self.id.is_empty() {
            c.push(at!["id"], "a material has an empty id".into());
        }
        let fields: [(Vec<Seg>, &str, f64, Range, &str); 6] = [
            (
                at!["youngs_modulus"],
                "youngs_modulus",
                self.youngs_modulus,
                Range::above(0.0, 1e6),
                " N/mm²",
            ),
            (
                at!["density"],
                "density",
                self.density,
                Range::above(0.0, 25_000.0),
                " kg/m³",
            ),
            (
                at!["yield_strength"],
                "yield_strength",
                self.yield_strength,
                Range::above(0.0, 10_000.0),
                " N/mm²",
            ),
            (
                at!["cutting", "cutting_speed"],
                "cutting.cutting_speed",
                self.cutting.cutting_speed,
                Range::closed(1.0, 10_000.0),
                " m/min",
            ),
            (
                at!["cutting", "feed_per_tooth_roughing"],
                "cutting.feed_per_tooth_roughing",
                self.cutting.feed_per_tooth_roughing,
                Range::closed(0.001, 2.0),
                " mm",
            ),
            (
                at!["cutting", "feed_per_tooth_finishing"],
                "cutting.feed_per_tooth_finishing",
                self.cutting.feed_per_tooth_finishing,
                Range::closed(0.001, 2.0),
                " mm",
            ),
        ];
        for (at, name, v, r, unit) in fields {
            c.range(at, &p, name, v, r, unit);
        }
    }
}
