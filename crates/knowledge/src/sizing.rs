//! Constants of the wall machining-feature sizing model (thesis §4.1.2,
//! table 4.1, appendix A table A.2), read from `knowledge/sizing.ron`.
//!
//! Lengths are in mm, forces in N. The model itself lives in
//! `thinplan-sizing`; this is only its data and the checks on it.

use serde::{Deserialize, Serialize};

use crate::at;
use crate::check::{Checks, Range, Seg};
use crate::TOOL_DIAMETER;

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
        let mut c = Checks::default();
        self.checks(&mut c);
        c.messages()
    }

    /// Problems with the values, each at its place in `sizing.ron`. Lower
    /// bounds on steps (depths and widths of cut, ≥ 0.01 mm) keep the
    /// number of heights and widths tried over a 1 m wall at most 10⁵.
    pub fn checks(&self, c: &mut Checks) {
        let step = Range::closed(0.01, 1000.0);
        let factor = Range::above(0.0, 100.0);
        let fields: [(Vec<Seg>, &str, f64, Range, &str); 14] = [
            (
                at!["allowed_deflection"],
                "`allowed_deflection`",
                self.allowed_deflection,
                Range::above(0.0, 10.0),
                " mm",
            ),
            (
                at!["effective_length_factor"],
                "`effective_length_factor`",
                self.effective_length_factor,
                factor,
                "",
            ),
            (
                at!["max_milling_force"],
                "`max_milling_force`",
                self.max_milling_force,
                Range::above(0.0, 1e5),
                " N",
            ),
            (
                at!["preferred_tool_diameter"],
                "`preferred_tool_diameter`",
                self.preferred_tool_diameter,
                TOOL_DIAMETER,
                " mm",
            ),
            (
                at!["width_rule_of_thumb", "max_height_to_stepped_thickness"],
                "`width_rule_of_thumb.max_height_to_stepped_thickness`",
                self.width_rule_of_thumb.max_height_to_stepped_thickness,
                Range::above(0.0, 1000.0),
                "",
            ),
            (
                at!["peripheral", "danger_zone_factor"],
                "`peripheral.danger_zone_factor`",
                self.peripheral.danger_zone_factor,
                Range::above(0.0, 10.0),
                " (fraction of D)",
            ),
            (
                at!["peripheral", "finishing_width_of_cut"],
                "`peripheral.finishing_width_of_cut`",
                self.peripheral.finishing_width_of_cut,
                step,
                " mm",
            ),
            (
                at!["peripheral", "roughing_stepover"],
                "`peripheral.roughing_stepover`",
                self.peripheral.roughing_stepover,
                Range::closed(0.01, 1.0),
                " (a fraction of the tool diameter)",
            ),
            (
                at!["peripheral", "finishing_depth_of_cut"],
                "`peripheral.finishing_depth_of_cut`",
                self.peripheral.finishing_depth_of_cut,
                step,
                " mm",
            ),
            (
                at!["face", "danger_zone_factor"],
                "`face.danger_zone_factor`",
                self.face.danger_zone_factor,
                Range::above(0.0, 10.0),
                " (fraction of D)",
            ),
            (
                at!["face", "finishing_depth_of_cut"],
                "`face.finishing_depth_of_cut`",
                self.face.finishing_depth_of_cut,
                step,
                " mm",
            ),
            (
                at!["face", "roughing_depth_of_cut"],
                "`face.roughing_depth_of_cut`",
                self.face.roughing_depth_of_cut,
                step,
                " mm",
            ),
            (
                at!["face", "finishing_width_of_cut_factor"],
                "`face.finishing_width_of_cut_factor`",
                self.face.finishing_width_of_cut_factor,
                Range::closed(0.01, 10.0),
                " (fraction of D)",
            ),
            (
                at!["face", "finishing_width_of_cut_extra"],
                "`face.finishing_width_of_cut_extra`",
                self.face.finishing_width_of_cut_extra,
                Range::closed(0.0, 1000.0),
                " mm",
            ),
        ];
        for (at, name, v, r, unit) in fields {
            c.range(at, "", name, v, r, unit);
        }
        c.count(
            at!["initial_height_ratio"],
            "",
            "`initial_height_ratio` (H/h)",
            self.initial_height_ratio,
            1,
            100,
        );
        for (mode, s) in [
            (
                "peripheral",
                (
                    self.peripheral.initial_finishing_cuts_in_h,
                    self.peripheral.min_cuts_in_width,
                    self.peripheral.max_cuts_in_width,
                ),
            ),
            (
                "face",
                (
                    self.face.initial_finishing_cuts_in_h,
                    self.face.min_cuts_in_width,
                    self.face.max_cuts_in_width,
                ),
            ),
        ] {
            let (initial, min, max) = s;
            c.count(
                at![mode, "initial_finishing_cuts_in_h"],
                "",
                &format!("`{mode}.initial_finishing_cuts_in_h`"),
                initial,
                1,
                1000,
            );
            c.count(
                at![mode, "min_cuts_in_width"],
                "",
                &format!("`{mode}.min_cuts_in_width`"),
                min,
                1,
                1000,
            );
            c.count(
                at![mode, "max_cuts_in_width"],
                "",
                &format!("`{mode}.max_cuts_in_width`"),
                max,
                min.max(1),
                1000,
            );
        }
        if let Some(t) = &self.tall_wall {
            c.range(
                at!["tall_wall", "tall_above_h_multiple"],
                "",
                "`tall_wall.tall_above_h_multiple`",
                t.tall_above_h_multiple,
                Range::closed(1.0, 1000.0),
                "",
            );
            let r = Range::closed(1.0, 1000.0);
            if !r.contains(t.max_big_h_over_h) {
                c.range(
                    at!["tall_wall", "max_big_h_over_h"],
                    "",
                    "`tall_wall.max_big_h_over_h`",
                    t.max_big_h_over_h,
                    r,
                    " (H ≥ h)",
                );
            } else if f64::from(self.initial_height_ratio) > t.max_big_h_over_h {
                c.push(
                    at!["initial_height_ratio"],
                    format!(
                        "`initial_height_ratio` ({}) exceeds `tall_wall.max_big_h_over_h` ({}): \
                         the initial sizes would break the tall-wall rule",
                        self.initial_height_ratio, t.max_big_h_over_h
                    ),
                );
            }
        }
    }
}
