//! Tool shapes (flat, bull-nose and ball end mills) and a LinuxCNC tool
//! table reader.
//!
//! Tool-table convention: one tool a line, `T<n> P<pocket> D<diameter>
//! [Z… and other offsets] ;comment`. The comment may hold a token
//! `r<value>` (e.g. `;em12 r0.5`): the corner radius in mm; the token `ball`
//! makes a ball end mill (corner radius = D/2). With neither it is a flat end
//! mill. Lines that are blank or only a comment are skipped.

use std::collections::BTreeMap;

use serde::Serialize;

use crate::gcode::GcodeError;

/// The kind of end mill, from its corner radius.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum ToolKind {
    Flat,
    BullNose,
    Ball,
}

/// The cutting end of a tool, rotating about +Z, tip at the programmed point.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ToolShape {
    pub diameter: f64,
    pub corner_radius: f64,
}

impl ToolShape {
    /// A flat end mill.
    pub fn flat(diameter: f64) -> Self {
        ToolShape {
            diameter,
            corner_radius: 0.0,
        }
    }

    /// A bull-nose end mill (corner radius `r`, clamped to `[0, D/2]`).
    pub fn bull(diameter: f64, r: f64) -> Self {
        ToolShape {
            diameter,
            corner_radius: r.clamp(0.0, diameter / 2.0),
        }
    }

    /// A ball end mill.
    pub fn ball(diameter: f64) -> Self {
        ToolShape {
            diameter,
            corner_radius: diameter / 2.0,
        }
    }

    pub fn radius(&self) -> f64 {
        self.diameter / 2.0
    }

    pub fn kind(&self) -> ToolKind {
        if self.corner_radius <= 0.0 {
            ToolKind::Flat
        } else if self.corner_radius >= self.radius() - 1e-12 {
            ToolKind::Ball
        } else {
            ToolKind::BullNose
        }
    }

    /// Height of the tool's lower surface above its tip at radial distance
    /// `rho`, or `None` outside the tool.
    #[inline]
    pub fn height_at(&self, rho: f64) -> Option<f64> {
        let r = self.radius();
        if rho > r {
            return None;
        }
        let core = r - self.corner_radius;
        if rho <= core {
            Some(0.0)
        } else {
            let u = rho - core;
            let rc = self.corner_radius;
            Some(rc - (rc * rc - u * u).max(0.0).sqrt())
        }
    }

    fn validate(&self) -> Result<(), String> {
        if !(self.diameter.is_finite() && self.diameter > 0.0 && self.diameter < 1e4) {
            return Err(format!("tool diameter {} must be positive", self.diameter));
        }
        if !(self.corner_radius >= 0.0 && self.corner_radius <= self.radius() + 1e-9) {
            return Err(format!(
                "corner radius {} must be between 0 and D/2 = {}",
                self.corner_radius,
                self.radius()
            ));
        }
        Ok(())
    }
}

/// Tools by number.
pub type ToolLibrary = BTreeMap<u32, ToolShape>;

/// Reads a LinuxCNC tool table (see the module doc for the comment
/// convention). Errors name `file:line:column`.
pub fn parse_tool_table(text: &str, file: &str) -> Result<ToolLibrary, GcodeError> {
    let mut lib = ToolLibrary::new();
    for (i, raw) in text.lines().enumerate() {
        let line = i + 1;
        let err = |col: usize, msg: String| GcodeError {
            file: file.to_string(),
            line,
            column: col,
            message: msg,
        };
        let (body, comment) = match raw.find(';') {
            Some(p) => (
                &raw[..p],
                Some((&raw[p + 1..], raw[..p].chars().count() + 2)),
            ),
            None => (raw, None),
        };
        let mut t = None;
        let mut d = None;
        let chars: Vec<char> = body.chars().collect();
        let mut k = 0;
        while k < chars.len() {
            let c = chars[k];
            if c.is_whitespace() {
                k += 1;
                continue;
            }
            let col = k + 1;
            if !c.is_ascii_alphabetic() {
                return Err(err(
                    col,
                    format!("unexpected character `{}`", c.escape_default()),
                ));
            }
            let letter = c.to_ascii_uppercase();
            if !"TPDXYZABCUVWIJQ".contains(letter) {
                return Err(err(col, format!("`{letter}` is not a tool-table word")));
            }
            k += 1;
            let start = k;
            while k < chars.len() && !chars[k].is_whitespace() {
                k += 1;
            }
            let s: String = chars[start..k].iter().collect();
            let v: f64 = s
                .parse()
                .ok()
                .filter(|v: &f64| v.is_finite())
                .ok_or_else(|| err(start + 1, format!("`{letter}` needs a number, found `{s}`")))?;
            match letter {
                'T' => {
                    if v < 1.0 || v.fract() != 0.0 || v > 1e6 {
                        return Err(err(
                            col,
                            format!("tool number `{s}` must be a whole number ≥ 1"),
                        ));
                    }
                    t = Some((v as u32, col));
                }
                'D' => d = Some(v),
                _ => {}
            }
        }
        let Some((num, tcol)) = t else {
            if chars.iter().all(|c| c.is_whitespace()) {
                continue;
            }
            return Err(err(1, "tool line without `T`".into()));
        };
        let Some(d) = d else {
            return Err(err(tcol, format!("tool T{num} has no diameter `D`")));
        };
        let mut shape = ToolShape::flat(d);
        if let Some((c, ccol)) = comment {
            for tok in c.split_whitespace() {
                if tok.eq_ignore_ascii_case("ball") {
                    shape = ToolShape::ball(d);
                } else if let Some(r) = tok.strip_prefix('r') {
                    if let Ok(r) = r.parse::<f64>() {
                        shape.corner_radius = r;
                    }
                }
            }
            shape
                .validate()
                .map_err(|m| err(ccol, format!("tool T{num}: {m}")))?;
        }
        shape
            .validate()
            .map_err(|m| err(tcol, format!("tool T{num}: {m}")))?;
        if lib.insert(num, shape).is_some() {
            return Err(err(tcol, format!("tool T{num} is listed twice")));
        }
    }
    Ok(lib)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn profile_heights() {
        let t = ToolShape::bull(12.0, 1.0);
        assert_eq!(t.height_at(4.9), Some(0.0));
        assert!((t.height_at(6.0).unwrap() - 1.0).abs() < 1e-12);
        assert_eq!(t.height_at(6.01), None);
        let b = ToolShape::ball(10.0);
        assert!((b.height_at(3.0).unwrap() - 1.0).abs() < 1e-12);
        assert_eq!(b.kind(), ToolKind::Ball);
        assert_eq!(ToolShape::flat(6.0).kind(), ToolKind::Flat);
        assert_eq!(t.kind(), ToolKind::BullNose);
    }

    #[test]
    fn reads_linuxcnc_table() {
        let lib = parse_tool_table(
            "T1 P1 D12.000 Z+0.000 ;em12 r0.5\n; a comment\n\nT2 P2 D20 Z+0 ;em20\nT3 P3 D6 ;ball6 ball\n",
            "tool.tbl",
        )
        .unwrap();
        assert_eq!(lib[&1], ToolShape::bull(12.0, 0.5));
        assert_eq!(lib[&2], ToolShape::flat(20.0));
        assert_eq!(lib[&3], ToolShape::ball(6.0));
    }

    #[test]
    fn table_errors_have_places() {
        let e = parse_tool_table("T1 P1 D12\nT2 P2 Dx\n", "t.tbl").unwrap_err();
        assert_eq!((e.line, e.column), (2, 8), "{e}");
        let e = parse_tool_table("T1 P1\n", "t.tbl").unwrap_err();
        assert!(e.to_string().contains("no diameter"), "{e}");
        let e = parse_tool_table("T1 P1 D6 ;x r4\n", "t.tbl").unwrap_err();
        assert!(e.to_string().starts_with("t.tbl:1:11:"), "{e}");
        let e = parse_tool_table("T1 D6\nT1 D8\n", "t.tbl").unwrap_err();
        assert!(e.to_string().contains("twice"), "{e}");
    }
}
