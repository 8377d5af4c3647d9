//! Machines, tools and materials: the resources a set-up names.

use serde::{Deserialize, Serialize};

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
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ToolSet {
    pub id: String,
    pub name: String,
    pub tools: Vec<Tool>,
}

impl ToolSet {
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
