//! Length and plane-angle units: SI and conversion-based units, and the
//! units a representation context assigns.

use crate::p21::Value;
use crate::StepErrorKind;

use super::args::{place_of, resolve_from, A};
use super::walk::Ctx;
use super::R;

/// Length and angle units of one representation context.
#[derive(Debug, Clone)]
pub(super) struct Units {
    /// Millimetres per file length unit.
    pub(super) length: f64,
    /// Radians per file angle unit.
    pub(super) angle: f64,
    pub(super) name: String,
    pub(super) declared: bool,
}

impl Units {
    pub(super) fn mm() -> Units {
        Units {
            length: 1.0,
            angle: 1.0,
            name: "mm".into(),
            declared: false,
        }
    }
}

impl<'x, 'a> Ctx<'x, 'a> {
    /// (kind, factor, name) of a unit: kind 'L' length (factor in mm),
    /// 'A' plane angle (factor in radians), '?' other. `None` for an entity
    /// that is no unit. A length or angle unit whose name is unknown or whose
    /// factor is not a positive finite number is an error naming it: a guess
    /// would scale the whole part.
    fn unit(&mut self, idx: usize, depth: usize) -> R<Option<(char, f64, String)>> {
        if depth > 8 {
            return Err(StepErrorKind::Limit {
                place: place_of(self.ex, idx),
                reason: "unit defined through more than 8 conversions".into(),
            });
        }
        self.tick(1, idx)?;
        let kind = if self.has_part(idx, "LENGTH_UNIT") {
            'L'
        } else if self.has_part(idx, "PLANE_ANGLE_UNIT") {
            'A'
        } else {
            '?'
        };
        let si = self
            .part_args(idx, "SI_UNIT")
            .or_else(|| (self.head(idx) == "SI_UNIT").then(|| self.args(idx)));
        if let Some(a) = si {
            return self.si_unit(&a, kind);
        }
        let Some(cbu) = self
            .part_args(idx, "CONVERSION_BASED_UNIT")
            .or_else(|| (self.head(idx) == "CONVERSION_BASED_UNIT").then(|| self.args(idx)))
        else {
            return Ok(None);
        };
        self.conversion_based_unit(&cbu, kind, depth)
    }

    /// An `SI_UNIT`: its prefix and name; `kind` is what the entity says it
    /// measures ('?' when it does not say).
    fn si_unit(&self, a: &A<'x, 'a>, kind: char) -> R<Option<(char, f64, String)>> {
        let n = a.vals.len();
        if n < 2 {
            return Ok(None);
        }
        let (prefix, name) = (&a.vals[n - 2], &a.vals[n - 1]);
        let name = match name {
            Value::Enum(s) => self.ex.raw(*s),
            _ => return Ok(None),
        };
        let (p, sym) = match prefix {
            Value::Enum(s) => match self.ex.raw(*s) {
                b"EXA" => (1e18, "E"),
                b"PETA" => (1e15, "P"),
                b"TERA" => (1e12, "T"),
                b"GIGA" => (1e9, "G"),
                b"MEGA" => (1e6, "M"),
                b"KILO" => (1e3, "k"),
                b"HECTO" => (1e2, "h"),
                b"DECA" => (1e1, "da"),
                b"DECI" => (1e-1, "d"),
                b"CENTI" => (1e-2, "c"),
                b"MILLI" => (1e-3, "m"),
                b"MICRO" => (1e-6, "u"),
                b"NANO" => (1e-9, "n"),
                b"PICO" => (1e-12, "p"),
                other if kind != '?' => {
                    return Err(a.wrong(format!(
                        "unknown SI prefix .{}.",
                        String::from_utf8_lossy(other)
                    )))
                }
                _ => (1.0, ""),
            },
            _ => (1.0, ""),
        };
        match (name, kind) {
            (b"METRE", 'L' | '?') => Ok(Some(('L', 1000.0 * p, format!("{sym}m")))),
            (b"RADIAN", 'A' | '?') => Ok(Some(('A', p, format!("{sym}rad")))),
            (_, '?') => Ok(Some(('?', 1.0, String::new()))),
            (other, k) => Err(a.wrong(format!(
                "unknown {} unit .{}.",
                if k == 'L' { "length" } else { "plane angle" },
                String::from_utf8_lossy(other)
            ))),
        }
    }

    /// A `CONVERSION_BASED_UNIT`: a known name, or its conversion factor
    /// from the unit it is measured in (which may be converted in turn).
    fn conversion_based_unit(
        &mut self,
        cbu: &A<'x, 'a>,
        mut kind: char,
        depth: usize,
    ) -> R<Option<(char, f64, String)>> {
        let name = cbu.string(0);
        let lname = name.trim().to_ascii_lowercase();
        let known = match lname.as_str() {
            "inch" | "in" => Some(('L', 25.4)),
            "foot" | "ft" => Some(('L', 304.8)),
            "yard" => Some(('L', 914.4)),
            "mile" => Some(('L', 1_609_344.0)),
            "degree" | "deg" => Some(('A', std::f64::consts::PI / 180.0)),
            "grad" | "gon" => Some(('A', std::f64::consts::PI / 200.0)),
            _ => None,
        };
        // The conversion factor: (measure entity, kind, factor).
        let mut from_measure = None;
        if let Ok(Some(m)) = cbu.opt_r(1) {
            let ma = if self.head(m).is_empty() {
                self.part_args(m, "MEASURE_WITH_UNIT")
            } else {
                let a = self.args(m);
                a.vals
                    .len()
                    .checked_sub(2)
                    .and_then(|k| a.vals.get(k..))
                    .map(|vals| A { vals, ..a })
            };
            if let Some(ma) = ma {
                let value = ma.num(0)?;
                if let Ok(Some(inner)) = ma.opt_r(1) {
                    if let Some((k, f, _)) = self.unit(inner, depth + 1)? {
                        from_measure = Some((m, ma, k, value * f));
                    }
                }
            }
        }
        if kind == '?' {
            kind = from_measure
                .as_ref()
                .map(|m| m.2)
                .or(known.map(|k| k.0))
                .unwrap_or('?');
        }
        if kind == '?' {
            // Not a unit a part's geometry is measured in.
            return Ok(Some(('?', 1.0, lname)));
        }
        let factor = match (from_measure, known) {
            (Some((_, ma, _, f)), _) => {
                if !(f.is_finite() && f > 0.0) {
                    return Err(ma.wrong(format!(
                        "conversion factor {f} of unit '{name}' is not a positive number"
                    )));
                }
                f
            }
            (None, Some((_, f))) => f,
            (None, None) => {
                return Err(cbu.wrong(format!(
                    "unknown unit name '{name}' without a conversion factor"
                )))
            }
        };
        Ok(Some((kind, factor, lname)))
    }

    pub(super) fn context_units(&mut self, ctx: Option<usize>) -> R<Units> {
        let Some(ctx) = ctx else {
            return Ok(Units::mm());
        };
        if let Some(u) = self.unit_cache.get(&ctx) {
            return Ok(u.clone());
        }
        let mut u = Units::mm();
        if let Some(a) = self.part_args(ctx, "GLOBAL_UNIT_ASSIGNED_CONTEXT") {
            if let Ok(list) = a.list(0) {
                for v in list {
                    let Ok(ui) = resolve_from(self.ex, ctx, v) else {
                        continue;
                    };
                    match self.unit(ui, 0)? {
                        Some(('L', f, name)) => {
                            u.length = f;
                            u.name = name;
                            u.declared = true;
                        }
                        Some(('A', f, _)) => u.angle = f,
                        _ => {}
                    }
                }
            }
        }
        self.unit_cache.insert(ctx, u.clone());
        Ok(u)
    }
}
