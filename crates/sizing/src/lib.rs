//! Wall machining-feature sizing: the stepped-cantilever bending model of
//! thesis §4.1.2 (figure 4.3, table 4.1, appendix A), as `docs/DESIGN.md`
//! reads it, and the rounded iteration that picks B_RF, h and H.
//!
//! A wall (length L, final thickness t, height H_w) is a cantilever clamped
//! at its base. Side A carries the large machining features (height H), side
//! B the small ones (height h), both B_RF wide. In the worst state (the first
//! large feature removed, the first small one just finished) the local
//! thickness, from the top down, is t over [0, h], t + B_RF over [h, H] and
//! t + 2·B_RF below H. The maximum milling force F acts at point D, depth h
//! below the top; the deflection that counts is at E, the top of the tool's
//! vibration re-machining danger zone, d above D:
//! δ_E = δ_D + θ_D · d. See `README.md` for the formulas and the appendix A
//! table.
//!
//! All constants come from [`SizingKnowledge`] (`knowledge/sizing.ron`);
//! Young's modulus comes from the material.

pub use thinplan_knowledge::{SizingKnowledge, TallWallRule};

/// How the wall's machining features are finished.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum MillingMode {
    /// Tool axis along the wall (side of the tool cuts): danger zone ¾·D.
    Peripheral,
    /// Tool axis across the wall (end of the tool cuts): danger zone ½·D.
    Face,
}

impl MillingMode {
    pub fn name(self) -> &'static str {
        match self {
            MillingMode::Peripheral => "peripheral",
            MillingMode::Face => "face",
        }
    }
}

/// A straight wall, mm.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Wall {
    /// L
    pub length: f64,
    /// Final thickness t.
    pub thickness: f64,
    /// H_w
    pub height: f64,
}

/// Machining-feature sizes, mm.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sizes {
    /// Width B_RF of every machining feature of the wall.
    pub b_rf: f64,
    /// Height h of the small features (side B).
    pub h: f64,
    /// Height H of the large features (side A).
    pub big_h: f64,
}

/// The result of [`size_wall`].
#[derive(Debug, Clone, PartialEq)]
pub struct StepSizes {
    pub b_rf: f64,
    pub h: f64,
    pub big_h: f64,
    /// δ_E for these sizes, mm.
    pub deflection: f64,
    /// How many deflections the iteration evaluated.
    pub iterations: u32,
    /// The values used, by name (constants, derived cut sizes, start values).
    pub provenance: Vec<(String, f64)>,
}

impl StepSizes {
    pub fn sizes(&self) -> Sizes {
        Sizes {
            b_rf: self.b_rf,
            h: self.h,
            big_h: self.big_h,
        }
    }
}

/// Why no sizes came out.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SizingError {
    /// Even the widest B_RF the knowledge allows, with the smallest h, bends
    /// the wall more than allowed.
    #[error(
        "no machining-feature sizes keep the wall {}×{}×{} mm within {allowed} mm: \
         the stiffest tried (B_RF = {}, h = {}, H = {}) deflects {deflection:.4} mm",
        wall.length, wall.thickness, wall.height, stiffest.b_rf, stiffest.h, stiffest.big_h
    )]
    Impossible {
        wall: Wall,
        stiffest: Sizes,
        deflection: f64,
        allowed: f64,
        iterations: u32,
        provenance: Vec<(String, f64)>,
    },
    /// A wall, modulus or knowledge value the model cannot use.
    #[error("sizing input: {0}")]
    InvalidInput(String),
}

/// The cut sizes that sizes are rounded to (table 4.1), for one mode.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CutSizes {
    /// Danger zone d above D, mm.
    pub danger_zone: f64,
    /// The first (finishing) part of a width, mm.
    pub width_first: f64,
    /// Each further (roughing) cut of a width, mm.
    pub width_step: f64,
    /// One finishing cut in height, mm: heights are whole multiples.
    pub height_step: f64,
    pub initial_h_cuts: u32,
    pub min_width_cuts: u32,
    pub max_width_cuts: u32,
}

impl CutSizes {
    /// Peripheral: B_RF = a_ef + n · stepover · D, heights n · finishing a_p.
    /// Face: B_RF = finishing depth + n · roughing depth, heights
    /// n · (½·D + 1).
    pub fn new(k: &SizingKnowledge, mode: MillingMode) -> CutSizes {
        let d = k.preferred_tool_diameter;
        match mode {
            MillingMode::Peripheral => {
                let p = &k.peripheral;
                CutSizes {
                    danger_zone: p.danger_zone_factor * d,
                    width_first: p.finishing_width_of_cut,
                    width_step: p.roughing_stepover * d,
                    height_step: p.finishing_depth_of_cut,
                    initial_h_cuts: p.initial_finishing_cuts_in_h,
                    min_width_cuts: p.min_cuts_in_width,
                    max_width_cuts: p.max_cuts_in_width,
                }
            }
            MillingMode::Face => {
                let f = &k.face;
                CutSizes {
                    danger_zone: f.danger_zone_factor * d,
                    width_first: f.finishing_depth_of_cut,
                    width_step: f.roughing_depth_of_cut,
                    height_step: f.finishing_width_of_cut_factor * d
                        + f.finishing_width_of_cut_extra,
                    initial_h_cuts: f.initial_finishing_cuts_in_h,
                    min_width_cuts: f.min_cuts_in_width,
                    max_width_cuts: f.max_cuts_in_width,
                }
            }
        }
    }

    /// The width of `cuts` cuts (the finishing cut included; `cuts ≥ 1`).
    pub fn width(&self, cuts: u32) -> f64 {
        self.width_first + f64::from(cuts.saturating_sub(1)) * self.width_step
    }

    /// The fewest cuts whose width is at least `b` (widths round up).
    pub fn width_cuts_at_least(&self, b: f64) -> u32 {
        if b <= self.width_first {
            return 1;
        }
        let n = ((b - self.width_first) / self.width_step - 1e-9).ceil();
        (n as u32).saturating_add(1)
    }

    /// The most whole height cuts in `height` (heights round down).
    pub fn height_cuts_at_most(&self, height: f64) -> u32 {
        (height / self.height_step + 1e-9).floor().max(0.0) as u32
    }
}

/// One piece of a stepped cantilever: constant bending stiffness `ei`
/// (N·mm²) from `from` to `to`, distances measured from the load point
/// towards the clamp.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Piece {
    pub from: f64,
    pub to: f64,
    pub ei: f64,
}

/// Deflection and slope at the load point of a cantilever made of
/// `pieces` (contiguous from 0 at the load to the clamp at the last `to`),
/// loaded by `force` at its free end.
///
/// With x measured from the load towards the clamp (at x = c), the moment
/// is M(x) = F·x. The clamp holds w(c) = w'(c) = 0, so
///
/// θ(x) = ∫ₓᶜ M(s)/EI(s) ds,   θ_D = θ(0) = ∫₀ᶜ F·s/EI(s) ds,
/// δ(x) = ∫ₓᶜ θ(s) ds,        δ_D = ∫₀ᶜ ∫ₛᶜ F·u/EI(u) du ds = ∫₀ᶜ F·u²/EI(u) du
///
/// (swapping the order of integration). For a piece [a, b] of constant EI
/// this gives θ += F·(b² − a²)/(2·EI) and δ += F·(b³ − a³)/(3·EI); one
/// uniform piece [0, L] gives the textbook F·L²/(2EI) and F·L³/(3EI).
/// Returns `(δ_D, θ_D)`.
pub fn stepped_cantilever(force: f64, pieces: &[Piece]) -> (f64, f64) {
    let mut delta = 0.0;
    let mut theta = 0.0;
    for p in pieces {
        if p.to <= p.from {
            continue;
        }
        delta += force * (p.to.powi(3) - p.from.powi(3)) / (3.0 * p.ei);
        theta += force * (p.to.powi(2) - p.from.powi(2)) / (2.0 * p.ei);
    }
    (delta, theta)
}

/// The bending of a wall for given sizes, with its parts.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Bending {
    /// L_e = min(L, k·H_w), mm.
    pub effective_length: f64,
    /// d, mm.
    pub danger_zone: f64,
    /// Deflection at D, mm.
    pub delta_d: f64,
    /// Slope at D, rad.
    pub theta_d: f64,
    /// δ_E = δ_D + θ_D·d, mm.
    pub delta_e: f64,
}

fn check_wall(wall: &Wall, e_modulus: f64) -> Result<(), SizingError> {
    for (n, v) in [
        ("wall length", wall.length),
        ("wall thickness", wall.thickness),
        ("wall height", wall.height),
        ("Young's modulus", e_modulus),
    ] {
        if !(v.is_finite() && v > 0.0) {
            return Err(SizingError::InvalidInput(format!(
                "{n} must be a positive number, not {v}"
            )));
        }
    }
    Ok(())
}

fn check_knowledge(k: &SizingKnowledge) -> Result<(), SizingError> {
    let problems = k.problems();
    if problems.is_empty() {
        Ok(())
    } else {
        Err(SizingError::InvalidInput(format!(
            "sizing knowledge: {}",
            problems.join("; ")
        )))
    }
}

/// The bending model for given sizes. Heights are clipped to the wall
/// (h ≤ H_w, h ≤ H ≤ H_w); the thin top [0, h] carries no moment (the load
/// is at its bottom), so only t + B_RF over [h, H] and t + 2·B_RF below H
/// bend.
pub fn bending(
    wall: &Wall,
    sizes: &Sizes,
    k: &SizingKnowledge,
    e_modulus: f64,
    mode: MillingMode,
) -> Result<Bending, SizingError> {
    check_wall(wall, e_modulus)?;
    for (n, v) in [
        ("B_RF", sizes.b_rf),
        ("h", sizes.h),
        ("H", sizes.big_h),
        ("allowed deflection", k.allowed_deflection),
        ("milling force", k.max_milling_force),
        ("effective length factor", k.effective_length_factor),
    ] {
        if !(v.is_finite() && v >= 0.0) {
            return Err(SizingError::InvalidInput(format!(
                "{n} must be zero or positive, not {v}"
            )));
        }
    }
    let cuts = CutSizes::new(k, mode);
    let hw = wall.height;
    let le = wall.length.min(k.effective_length_factor * hw);
    let h = sizes.h.min(hw);
    let big_h = sizes.big_h.clamp(h, hw);
    let ei = |s: f64| e_modulus * le * s.powi(3) / 12.0;
    let t = wall.thickness;
    let pieces = [
        Piece {
            from: 0.0,
            to: big_h - h,
            ei: ei(t + sizes.b_rf),
        },
        Piece {
            from: big_h - h,
            to: hw - h,
            ei: ei(t + 2.0 * sizes.b_rf),
        },
    ];
    let (delta_d, theta_d) = stepped_cantilever(k.max_milling_force, &pieces);
    Ok(Bending {
        effective_length: le,
        danger_zone: cuts.danger_zone,
        delta_d,
        theta_d,
        delta_e: delta_d + theta_d * cuts.danger_zone,
    })
}

/// δ_E (mm) of `wall` machined with `sizes`: the modelled deflection at the
/// top of the danger zone. NaN for inputs the model cannot use (see
/// [`bending`] for the reason).
pub fn deflection(
    wall: &Wall,
    sizes: &Sizes,
    k: &SizingKnowledge,
    e_modulus: f64,
    mode: MillingMode,
) -> f64 {
    bending(wall, sizes, k, e_modulus, mode).map_or(f64::NAN, |b| b.delta_e)
}

/// Whether the knowledge's tall-wall rule (if any) allows these sizes.
pub fn tall_wall_allows(k: &SizingKnowledge, wall: &Wall, sizes: &Sizes) -> bool {
    k.tall_wall
        .as_ref()
        .is_none_or(|r| r.allows(wall.height, sizes.h, sizes.big_h))
}

/// Picks B_RF, h and H for a wall by the iteration of §4.1.2, in rounded
/// steps (table 4.1: widths rounded up, heights down to whole cuts):
///
/// 1. B_RF from the stiffness rule of thumb (t + B_RF ≥ H_w / s), rounded
///    up to whole cuts and to at least the mode's minimum number of cuts;
///    h = the initial number of finishing cuts (at most the wall height);
///    H = ratio · h (at most H_w, and what the tall-wall rule allows).
/// 2. While δ_E > allowed, h loses one finishing cut (never below one) and
///    H is reset to ratio · h.
/// 3. If still too large at one cut, B_RF widens by one roughing cut and
///    step 2 starts again from the initial h; past the knowledge's widest
///    B_RF the wall is [`SizingError::Impossible`].
/// 4. H grows in steps of h while δ_E ≤ allowed and H ≤ H_w; heights the
///    tall-wall rule forbids are stepped over, not taken.
///
/// A wall lower than one finishing cut is finished in one cut: h = H = H_w.
pub fn size_wall(
    wall: &Wall,
    k: &SizingKnowledge,
    e_modulus: f64,
    mode: MillingMode,
) -> Result<StepSizes, SizingError> {
    check_wall(wall, e_modulus)?;
    check_knowledge(k)?;
    let cuts = CutSizes::new(k, mode);
    let m = mode.name();
    let hw = wall.height;
    let allowed = k.allowed_deflection;
    let ratio = k.initial_height_ratio;

    let mut iterations = 0u32;
    let mut eval = |s: &Sizes| -> f64 {
        iterations += 1;
        deflection(wall, s, k, e_modulus, mode)
    };

    // Start values.
    let b_thumb =
        (hw / k.width_rule_of_thumb.max_height_to_stepped_thickness - wall.thickness).max(0.0);
    let n_b0 = cuts
        .width_cuts_at_least(b_thumb)
        .max(cuts.min_width_cuts)
        .min(cuts.max_width_cuts);
    let n_h_wall = cuts.height_cuts_at_most(hw);
    let n_h0 = cuts.initial_h_cuts.min(n_h_wall);

    let mut provenance: Vec<(String, f64)> = vec![
        ("allowed_deflection".into(), allowed),
        ("max_milling_force".into(), k.max_milling_force),
        ("e_modulus".into(), e_modulus),
        ("effective_length_factor".into(), k.effective_length_factor),
        (
            "effective_length".into(),
            wall.length.min(k.effective_length_factor * hw),
        ),
        ("preferred_tool_diameter".into(), k.preferred_tool_diameter),
        (format!("{m}.danger_zone"), cuts.danger_zone),
        (format!("{m}.width_first_cut"), cuts.width_first),
        (format!("{m}.width_step"), cuts.width_step),
        (format!("{m}.height_step"), cuts.height_step),
        (
            format!("{m}.initial_finishing_cuts_in_h"),
            f64::from(cuts.initial_h_cuts),
        ),
        (
            format!("{m}.min_cuts_in_width"),
            f64::from(cuts.min_width_cuts),
        ),
        (
            format!("{m}.max_cuts_in_width"),
            f64::from(cuts.max_width_cuts),
        ),
        ("initial_height_ratio".into(), f64::from(ratio)),
        (
            "width_rule_of_thumb.max_height_to_stepped_thickness".into(),
            k.width_rule_of_thumb.max_height_to_stepped_thickness,
        ),
        ("b_rf_rule_of_thumb".into(), b_thumb),
        ("b_rf_initial".into(), cuts.width(n_b0)),
        ("h_initial".into(), f64::from(n_h0) * cuts.height_step),
    ];
    if let Some(r) = &k.tall_wall {
        provenance.push((
            "tall_wall.tall_above_h_multiple".into(),
            r.tall_above_h_multiple,
        ));
        provenance.push(("tall_wall.max_big_h_over_h".into(), r.max_big_h_over_h));
        provenance.push((
            "tall_wall.full_height_exempt".into(),
            if r.full_height_exempt { 1.0 } else { 0.0 },
        ));
    }

    if n_h_wall == 0 {
        // Lower than one finishing cut: one cut over the whole height.
        let s = Sizes {
            b_rf: cuts.width(n_b0),
            h: hw,
            big_h: hw,
        };
        let deflection = eval(&s);
        provenance.push(("wall_lower_than_one_cut".into(), 1.0));
        return Ok(StepSizes {
            b_rf: s.b_rf,
            h: s.h,
            big_h: s.big_h,
            deflection,
            iterations,
            provenance,
        });
    }

    // H for h = n_h cuts: the largest multiple of h up to ratio·h, within
    // the wall and allowed by the tall-wall rule (one h always is).
    let reset_big_h = |b: f64, n_h: u32| -> u32 {
        let h = f64::from(n_h) * cuts.height_step;
        let most = ratio.min(n_h_wall / n_h).max(1);
        (1..=most)
            .rev()
            .find(|&mult| {
                tall_wall_allows(
                    k,
                    wall,
                    &Sizes {
                        b_rf: b,
                        h,
                        big_h: f64::from(mult * n_h) * cuts.height_step,
                    },
                )
            })
            .unwrap_or(1)
    };
    let sizes_of = |n_b: u32, n_h: u32, mult: u32| Sizes {
        b_rf: cuts.width(n_b),
        h: f64::from(n_h) * cuts.height_step,
        big_h: f64::from(mult * n_h) * cuts.height_step,
    };

    let mut found: Option<(u32, u32, u32, f64)> = None;
    let mut stiffest: Option<(Sizes, f64)> = None;
    'widths: for n_b in n_b0..=cuts.max_width_cuts {
        for n_h in (1..=n_h0).rev() {
            let mult = reset_big_h(cuts.width(n_b), n_h);
            let s = sizes_of(n_b, n_h, mult);
            let d = eval(&s);
            if stiffest.is_none_or(|(_, best)| d < best) {
                stiffest = Some((s, d));
            }
            if d <= allowed {
                found = Some((n_b, n_h, mult, d));
                break 'widths;
            }
        }
    }
    let Some((n_b, n_h, mut mult, mut delta)) = found else {
        let (stiffest, deflection) = stiffest.expect("at least one size was tried");
        return Err(SizingError::Impossible {
            wall: *wall,
            stiffest,
            deflection,
            allowed,
            iterations,
            provenance,
        });
    };

    // Grow H in steps of h.
    let mut next = mult + 1;
    while next * n_h <= n_h_wall {
        let s = sizes_of(n_b, n_h, next);
        let d = eval(&s);
        if d > allowed {
            break;
        }
        if tall_wall_allows(k, wall, &s) {
            mult = next;
            delta = d;
        }
        next += 1;
    }
    let s = sizes_of(n_b, n_h, mult);
    Ok(StepSizes {
        b_rf: s.b_rf,
        h: s.h,
        big_h: s.big_h,
        deflection: delta,
        iterations,
        provenance,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn width_and_height_rounding() {
        let k = thinplan_knowledge::Knowledge::builtin().unwrap().sizing;
        let p = CutSizes::new(&k, MillingMode::Peripheral);
        assert_eq!(p.width(2), 11.0);
        assert_eq!(p.width_cuts_at_least(11.0), 2);
        assert_eq!(p.width_cuts_at_least(11.01), 3);
        assert_eq!(p.width_cuts_at_least(0.5), 1);
        assert_eq!(p.height_cuts_at_most(12.0), 8);
        assert_eq!(p.height_cuts_at_most(13.4), 8);
        let f = CutSizes::new(&k, MillingMode::Face);
        assert_eq!(f.width(3), 10.0);
        assert_eq!(f.height_step, 7.0);
        assert_eq!(f.danger_zone, 6.0);
    }
}
