//! Post-processors as data (`knowledge/posts/*.ron`): every difference
//! between G-code dialects lives here, never in the output stage's code.
//!
//! Text blocks are templates: `{name}` is replaced by a value the output
//! stage knows (see [`PROGRAM_PLACEHOLDERS`] and [`OPERATION_PLACEHOLDERS`]);
//! `{{` and `}}` stand for literal braces. An unknown placeholder is a
//! load-time error, so a typo never reaches a machine.

use serde::{Deserialize, Serialize};

use crate::at;
use crate::check::Checks;

/// Placeholders known in every template.
pub const PROGRAM_PLACEHOLDERS: &[&str] = &[
    "part",        // the part's source as the user gave it
    "sha256",      // the first 16 hex digits of the part file's SHA-256
    "up",          // the set-up's spindle axis, e.g. `0 0 1`
    "machine",     // machine id
    "tool_set",    // tool set id
    "material",    // material id
    "knowledge",   // where the knowledge came from (plan note `knowledge`)
    "version",     // thinplan's version
    "post",        // this post's id
    "post_name",   // this post's name
    "work_offset", // the post's work offset word, e.g. `G54`
    "clearance_z", // safe height: highest point of the program + `clearance`
    "tool_count",  // number of tool changes in the program
];

/// Placeholders known only in per-operation templates (tool change,
/// operation start, spindle on).
pub const OPERATION_PLACEHOLDERS: &[&str] = &[
    "tool",          // tool number: 1-based position in the set-up's tool set
    "tool_id",       // tool id in the tool set
    "tool_diameter", // mm, with the post's decimals
    "rpm",           // spindle speed, whole revolutions per minute
    "operation",     // operation id, e.g. `OP3`
    "feature",       // machining feature id, e.g. `MF2`
    "method",        // the operation's method name
];

/// How comments are written.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum CommentStyle {
    /// `(text)`; parentheses inside the text become brackets.
    Parentheses,
    /// `; text`
    Semicolon,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Comments {
    pub style: CommentStyle,
    /// Upper-case the comment text (controls that only know capitals).
    pub uppercase: bool,
    /// Replace characters outside printable ASCII with `?`.
    pub ascii_only: bool,
}

/// Block numbers (`N10`, `N20` …) on code blocks; raw lines never get one.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LineNumbers {
    pub enabled: bool,
    pub start: u32,
    pub step: u32,
}

/// One line of a template list.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum Block {
    /// A G-code block: numbered when line numbers are on.
    Code(String),
    /// A comment, written in the post's comment style.
    Comment(String),
    /// Written as is, never numbered (`%`, `O0001`).
    Raw(String),
}

impl Block {
    pub fn text(&self) -> &str {
        match self {
            Block::Code(t) | Block::Comment(t) | Block::Raw(t) => t,
        }
    }
}

/// The words of motion blocks.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MotionWords {
    pub rapid: String,
    pub linear: String,
    /// Clockwise arc seen from +Z (looking down at the XY plane).
    pub arc_cw: String,
    pub arc_ccw: String,
    pub feed: String,
}

/// How circular arcs of the tool path are written.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ArcOutput {
    /// Write arcs in the XY plane as G2/G3 with I J (incremental, from the
    /// arc's start); when false every arc is linearised.
    pub enabled: bool,
    /// Whether an XY arc may change Z along the way (a helix).
    pub helical: bool,
    /// Arcs with a larger radius (mm) are linearised: controls lose
    /// precision on near-straight arcs.
    pub max_radius: f64,
    /// Arcs with a smaller radius (mm) are linearised (I J would round badly).
    pub min_radius: f64,
    /// Largest distance (mm) between a linearised arc and its chords.
    pub chord_tolerance: f64,
}

/// A post-processor: one G-code dialect and the shop's conventions.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PostProcessor {
    pub id: String,
    pub name: String,
    /// File extension of programs, without the dot (`ngc`, `nc`).
    pub extension: String,
    pub comments: Comments,
    pub line_numbers: LineNumbers,
    /// Decimals of coordinates and arc offsets (fixed, never `-0.000`).
    pub decimals: u32,
    /// Decimals of feed rates.
    pub feed_decimals: u32,
    pub motion: MotionWords,
    /// The work offset word, available as `{work_offset}`.
    pub work_offset: String,
    /// Safe height above the highest point of the program, mm.
    pub clearance: f64,
    /// Comments at the top of the program (program placeholders).
    pub header: Vec<Block>,
    /// Blocks after the header: units, plane, modes, work offset.
    pub program_start: Vec<Block>,
    /// Blocks moving the tool to a safe place; written before every tool
    /// change and at the end (program placeholders).
    pub safe_retract: Vec<Block>,
    /// Blocks changing to `{tool}`; written only when the tool changes.
    pub tool_change: Vec<Block>,
    /// Blocks at the start of every operation (spindle speed per operation).
    pub operation_start: Vec<Block>,
    /// Spindle on at `{rpm}`, per operation.
    pub spindle_on: Vec<Block>,
    pub spindle_off: Vec<Block>,
    pub coolant_on: Vec<Block>,
    pub coolant_off: Vec<Block>,
    pub program_end: Vec<Block>,
    pub arcs: ArcOutput,
}

/// The placeholders of a template, in order, or why it is malformed.
pub fn placeholders(template: &str) -> Result<Vec<&str>, String> {
    let mut out = Vec::new();
    let mut rest = template;
    while let Some(i) = rest.find(['{', '}']) {
        let (c, after) = (rest.as_bytes()[i], &rest[i + 1..]);
        if after.as_bytes().first() == Some(&c) {
            rest = &after[1..]; // `{{` or `}}`: a literal brace
            continue;
        }
        if c == b'}' {
            return Err(format!("a lone `}}` in `{template}` (write `}}}}`)"));
        }
        let Some(end) = after.find('}') else {
            return Err(format!("an unclosed `{{` in `{template}`"));
        };
        out.push(&after[..end]);
        rest = &after[end + 1..];
    }
    Ok(out)
}

/// Fills a template; `value` answers a placeholder or `None` if unknown.
pub fn fill(template: &str, value: impl Fn(&str) -> Option<String>) -> Result<String, String> {
    let mut out = String::with_capacity(template.len());
    let mut rest = template;
    while let Some(i) = rest.find(['{', '}']) {
        out.push_str(&rest[..i]);
        let (c, after) = (rest.as_bytes()[i], &rest[i + 1..]);
        if after.as_bytes().first() == Some(&c) {
            out.push(c as char);
            rest = &after[1..];
            continue;
        }
        if c == b'}' {
            return Err(format!("a lone `}}` in `{template}`"));
        }
        let Some(end) = after.find('}') else {
            return Err(format!("an unclosed `{{` in `{template}`"));
        };
        let name = &after[..end];
        match value(name) {
            Some(v) => out.push_str(&v),
            None => return Err(format!("unknown placeholder `{{{name}}}` in `{template}`")),
        }
        rest = &after[end + 1..];
    }
    out.push_str(rest);
    Ok(out)
}

impl PostProcessor {
    /// Problems a parser cannot find: unknown placeholders, bad numbers,
    /// empty words. Each sentence names the post and the field.
    pub fn problems(&self) -> Vec<String> {
        let mut c = Checks::default();
        self.checks(&mut c);
        c.messages()
    }

    /// The problems, each at its place in the post's file.
    pub fn checks(&self, c: &mut Checks) {
        let name = format!("post `{}`", self.id);
        if self.id.is_empty() {
            c.push(at!["id"], "a post has an empty id".to_string());
        }
        let program: Vec<&str> = PROGRAM_PLACEHOLDERS.to_vec();
        let operation: Vec<&str> = PROGRAM_PLACEHOLDERS
            .iter()
            .chain(OPERATION_PLACEHOLDERS)
            .copied()
            .collect();
        let lists: [(&'static str, &Vec<Block>, &Vec<&str>); 10] = [
            ("header", &self.header, &program),
            ("program_start", &self.program_start, &program),
            ("safe_retract", &self.safe_retract, &program),
            ("tool_change", &self.tool_change, &operation),
            ("operation_start", &self.operation_start, &operation),
            ("spindle_on", &self.spindle_on, &operation),
            ("spindle_off", &self.spindle_off, &program),
            ("coolant_on", &self.coolant_on, &program),
            ("coolant_off", &self.coolant_off, &program),
            ("program_end", &self.program_end, &program),
        ];
        for (field, blocks, known) in lists {
            for (i, b) in blocks.iter().enumerate() {
                let text = b.text();
                if text.contains(['\n', '\r']) {
                    c.push(
                        at![field, i],
                        format!("{name}: {field}[{i}] spans lines; write one block per line"),
                    );
                }
                match placeholders(text) {
                    Err(e) => c.push(at![field, i], format!("{name}: {field}[{i}]: {e}")),
                    Ok(ps) => {
                        for p in ps {
                            if !known.contains(&p) {
                                let hint = if OPERATION_PLACEHOLDERS.contains(&p) {
                                    " (it is known only in tool_change, operation_start \
                                     and spindle_on)"
                                        .to_string()
                                } else {
                                    format!(" (known here: {})", known.join(", "))
                                };
                                c.push(
                                    at![field, i],
                                    format!(
                                        "{name}: {field}[{i}]: unknown placeholder `{{{p}}}`{hint}"
                                    ),
                                );
                            }
                        }
                    }
                }
            }
        }
        if self.tool_change.is_empty() {
            c.push(at!["tool_change"], format!("{name}: tool_change is empty"));
        }
        if self.extension.is_empty() || self.extension.contains(['.', '/', '\\']) {
            c.push(
                at!["extension"],
                format!(
                    "{name}: extension `{}` must be a bare name like `ngc`",
                    self.extension
                ),
            );
        }
        if self.decimals > 6 || self.decimals == 0 {
            c.push(
                at!["decimals"],
                format!("{name}: decimals {} is outside 1..=6", self.decimals),
            );
        }
        if self.feed_decimals > 4 {
            c.push(
                at!["feed_decimals"],
                format!(
                    "{name}: feed_decimals {} is outside 0..=4",
                    self.feed_decimals
                ),
            );
        }
        if self.line_numbers.enabled && self.line_numbers.step == 0 {
            c.push(
                at!["line_numbers", "step"],
                format!("{name}: line_numbers.step must be at least 1"),
            );
        }
        let m = &self.motion;
        let words: [(&'static str, &String); 5] = [
            ("rapid", &m.rapid),
            ("linear", &m.linear),
            ("arc_cw", &m.arc_cw),
            ("arc_ccw", &m.arc_ccw),
            ("feed", &m.feed),
        ];
        for (w, v) in words {
            if v.trim().is_empty() {
                c.push(at!["motion", w], format!("{name}: motion.{w} is empty"));
            }
        }
        if !(self.clearance.is_finite() && self.clearance > 0.0) {
            c.push(
                at!["clearance"],
                format!(
                    "{name}: clearance must be a positive number, not {}",
                    self.clearance
                ),
            );
        }
        let a = &self.arcs;
        if !(a.chord_tolerance.is_finite() && a.chord_tolerance > 0.0) {
            c.push(
                at!["arcs", "chord_tolerance"],
                format!(
                    "{name}: arcs.chord_tolerance must be a positive number, not {}",
                    a.chord_tolerance
                ),
            );
        }
        let unit = 10f64.powi(-(self.decimals.min(6) as i32));
        if a.chord_tolerance > 0.0 && a.chord_tolerance < unit {
            c.push(
                at!["arcs", "chord_tolerance"],
                format!(
                    "{name}: arcs.chord_tolerance {} is finer than the output resolution {unit}",
                    a.chord_tolerance
                ),
            );
        }
        if !(a.min_radius.is_finite() && a.min_radius >= 0.0) {
            c.push(
                at!["arcs", "min_radius"],
                format!("{name}: arcs.min_radius must be ≥ 0, not {}", a.min_radius),
            );
        }
        if !(a.max_radius.is_finite() && a.max_radius > a.min_radius) {
            c.push(
                at!["arcs", "max_radius"],
                format!(
                    "{name}: arcs.max_radius {} must exceed min_radius {}",
                    a.max_radius, a.min_radius
                ),
            );
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn placeholders_and_escapes() {
        assert_eq!(placeholders("T{tool} M6 {{x}}").unwrap(), vec!["tool"]);
        assert!(placeholders("T{tool").is_err());
        assert!(placeholders("a } b").is_err());
        let v = |n: &str| (n == "tool").then(|| "3".to_string());
        assert_eq!(fill("T{tool} M6 {{x}}", v).unwrap(), "T3 M6 {x}");
        assert!(fill("{rpm}", v).unwrap_err().contains("`{rpm}`"));
    }
}
