//! Constants of the wall machining-feature sizing model (thesis §4.1.2,
//! table 4.1, appendix A table A.2), read from `knowledge/sizing.ron`.
//!
//! Lengths are in mm, forces in N. The model itself lives in
//! `thinplan-sizing`; this is only its data and the checks on it.

use serde::{Deserialize, Serialize};

/// Everything the sizing model needs besides the wall and the material.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SizingKnowledge {
    /// Largest deflection allowed at point E, mm (table A.2: 0.01).
    pub allowed_deflection: f64,
    /// k in the effective length L_e = min(L, k · H_w) (table A.2: 4).
    pub effective_length_factor: f64,
    /// The load F, N (table A.2: 200).
    pub max_milling_force: f64,
    /// Preferred tool diameter D, mm (table A.2: 12).
    pub preferred_tool_diameter: f64,
    /// Initial H/h, a whole number so that H is a multiple of h (table A.2: 2).
    pub initial_height_ratio: u32,
    /// The stiffness rule of thumb for the initial B_RF.
    pub width_rule_of_thumb: WidthRuleOfThumb,
    pub peripheral: PeripheralSizing,
    pub face: FaceSizing,
    /// The tall-wall remark of appendix A test 10 as a rule; `None`: off.
    #[serde(default)]
    pub tall_wall: Option<TallWallRule>,
}

/// Initial B_RF: `t + B_RF ≥ H_w / max_height_to_stepped_thickness`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WidthRuleOfThumb {
    /// Largest H_w / (t + B_RF), dimensionless.
    pub max_height_to_stepped_thickness: f64,
}

/// Peripheral milling constants (table A.2).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PeripheralSizing {
    /// Danger zone d as a fraction of D (3/4).
    pub danger_zone_factor: f64,
    /// Finishing width of cut a_ef, mm (2).
    pub finishing_width_of_cut: f64,
    /// Roughing stepover as a fraction of D (0.75).
    pub roughing_stepover: f64,
    /// Finishing depth of cut, mm (1.5): the height step.
    pub finishing_depth_of_cut: f64,
    /// Initial number of finishing cuts in h (8).
    pub initial_finishing_cuts_in_h: u32,
    /// Fewest cuts in B_RF, the finishing cut included (2).
    pub min_cuts_in_width: u32,
    /// Most cuts in B_RF before the wall is reported impossible.
    pub max_cuts_in_width: u32,
}

/// Face milling constants (table A.2).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FaceSizing {
    /// Danger zone d as a fraction of D (1/2).
    pub danger_zone_factor: f64,
    /// Finishing depth of cut, mm (2): the first part of B_RF.
    pub finishing_depth_of_cut: f64,
    /// Roughing depth of cut, mm (4): the width step.
    pub roughing_depth_of_cut: f64,
    /// Finishing width of cut = factor · D + extra (1/2 · D + 1): the height step.
    pub finishing_width_of_cut_factor: f64,
    pub finishing_width_of_cut_extra: f64,
    /// Initial number of finishing cuts in h (3).
    pub initial_finishing_cuts_in_h: u32,
    /// Fewest cuts in B_RF, the finishing cut included (3).
    pub min_cuts_in_width: u32,
    /// Most cuts in B_RF before the wall is reported impossible.
    pub max_cuts_in_width: u32,
}

/// Appendix A, TEST10-0398-4A: "H = 4·h is good for a 48 mm high wall, but
/// this ratio is too great if the wall height exceeds 4·h".
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TallWallRule {
    /// The wall is tall when H_w > tall_above_h_multiple · h (4).
    pub tall_above_h_multiple: f64,
    /// On a tall wall, H/h ≤ this (3).
    pub max_big_h_over_h: f64,
    /// Whether H = H_w (one large feature over the whole wall) is exempt.
    pub full_height_exempt: bool,
}

impl TallWallRule {
    /// Whether the rule allows heights `h`, `big_h` on a wall of height
    /// `wall_height`.
    pub fn allows(&self, wall_height: f64, h: f64, big_h: f64) -> bool {
        let tol = 1e-9 * wall_height.abs().max(1.0);
        let tall = wall_height > self.tall_above_h_multiple * h + tol;
        if !tall {
            return true;
        }
        if self.full_height_exempt && big_h >= wall_height - tol {
            return true;
        }
        big_h <= self.max_big_h_over_h * h + tol
    }
}

impl SizingKnowledge {
    /// Problems with the values, one message each (empty: valid).
    pub fn problems(&self) -> Vec<String> {
        let mut out = Vec::new();
        let mut positive = |name: &str, v: f64| {
            if !(v.is_finite() && v > 0.0) {
                out.push(format!("`{name}` must be a positive number, not {v}"));
            }
        };
        positive("allowed_deflection", self.allowed_deflection);
        positive("effective_length_factor", self.effective_length_factor);
        positive("max_milling_force", self.max_milling_force);
        positive("preferred_tool_diameter", self.preferred_tool_diameter);
        positive(
            "width_rule_of_thumb.max_height_to_stepped_thickness",
            self.width_rule_of_thumb.max_height_to_stepped_thickness,
        );
        let p = &self.peripheral;
        positive("peripheral.danger_zone_factor", p.danger_zone_factor);
        positive(
            "peripheral.finishing_width_of_cut",
            p.finishing_width_of_cut,
        );
        positive("peripheral.roughing_stepover", p.roughing_stepover);
        positive(
            "peripheral.finishing_depth_of_cut",
            p.finishing_depth_of_cut,
        );
        let f = &self.face;
        positive("face.danger_zone_factor", f.danger_zone_factor);
        positive("face.finishing_depth_of_cut", f.finishing_depth_of_cut);
        positive("face.roughing_depth_of_cut", f.roughing_depth_of_cut);
        positive(
            "face.finishing_width_of_cut_factor",
            f.finishing_width_of_cut_factor,
        );
        if !(f.finishing_width_of_cut_extra.is_finite() && f.finishing_width_of_cut_extra >= 0.0) {
            out.push(format!(
                "`face.finishing_width_of_cut_extra` must be zero or positive, not {}",
                f.finishing_width_of_cut_extra
            ));
        }
        if p.roughing_stepover > 1.0 {
            out.push(format!(
                "`peripheral.roughing_stepover` is a fraction of the tool diameter and must lie in (0, 1], not {}",
                p.roughing_stepover
            ));
        }
        if self.initial_height_ratio < 1 {
            out.push("`initial_height_ratio` (H/h) must be at least 1".into());
        }
        for (mode, initial, min, max) in [
            (
                "peripheral",
                p.initial_finishing_cuts_in_h,
                p.min_cuts_in_width,
                p.max_cuts_in_width,
            ),
            (
                "face",
                f.initial_finishing_cuts_in_h,
                f.min_cuts_in_width,
                f.max_cuts_in_width,
            ),
        ] {
            if initial < 1 {
                out.push(format!(
                    "`{mode}.initial_finishing_cuts_in_h` must be at least 1"
                ));
            }
            if min < 1 {
                out.push(format!("`{mode}.min_cuts_in_width` must be at least 1"));
            }
            if max < min {
                out.push(format!(
                    "`{mode}.max_cuts_in_width` ({max}) is below `{mode}.min_cuts_in_width` ({min})"
                ));
            }
        }
        if let Some(t) = &self.tall_wall {
            if !(t.tall_above_h_multiple.is_finite() && t.tall_above_h_multiple >= 1.0) {
                out.push(format!(
                    "`tall_wall.tall_above_h_multiple` must be at least 1, not {}",
                    t.tall_above_h_multiple
                ));
            }
            if !(t.max_big_h_over_h.is_finite() && t.max_big_h_over_h >= 1.0) {
                out.push(format!(
                    "`tall_wall.max_big_h_over_h` must be at least 1 (H ≥ h), not {}",
                    t.max_big_h_over_h
                ));
            } else if f64::from(self.initial_height_ratio) > t.max_big_h_over_h {
                out.push(format!(
                    "`initial_height_ratio` ({}) exceeds `tall_wall.max_big_h_over_h` ({}): \
                     the initial sizes would break the tall-wall rule",
                    self.initial_height_ratio, t.max_big_h_over_h
                ));
            }
        }
        out
    }
}
