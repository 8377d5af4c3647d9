//! Stage 9 output: a plan's operations written as an NC program through a
//! post-processor read from knowledge (`knowledge/posts/*.ron`).
//!
//! Everything that differs between dialects (words, comments, line numbers,
//! tape marks, tool change, spindle, coolant, arcs) is data in the
//! [`PostProcessor`]; this crate only walks the operations and fills the
//! templates.
//!
//! Conventions:
//! - **Tool numbers** are the 1-based position of the operation's tool in the
//!   set-up's tool set (`T1` is the set's first tool); the tool table written
//!   beside the program uses the same numbers, pocket = tool number.
//! - Coordinates are the plan's part coordinates (the work offset's origin is
//!   the part origin). Only operations whose tool axis is +Z are posted
//!   (3-axis programs).
//! - Numbers have the post's fixed decimals and are never `-0.000`; every
//!   length reported in [`NcProgram`] is measured on the emitted (rounded)
//!   coordinates, as a controller reads them.
//! - Arcs about ±Z become G2/G3 with I J incremental from the emitted arc
//!   start (helical when Z changes); any other arc, or one outside the
//!   post's radius range, becomes line segments within its chord tolerance.

use std::collections::BTreeMap;
use std::f64::consts::TAU;
use std::fmt::Write as _;

use glam::{DVec2, DVec3};
use thinplan_knowledge::posts::{fill, Block, CommentStyle};
use thinplan_knowledge::{PostProcessor, ToolSet};
use thinplan_plan::{Operation, OperationId, PathMove, Plan};

/// A posted program and what it measures.
#[derive(Debug, Clone, PartialEq)]
pub struct NcProgram {
    /// The program text, lines ending in `\n`.
    pub text: String,
    /// The LinuxCNC tool table (`.tbl`) for the set-up's tool set.
    pub tool_table: String,
    /// The post's file extension (without the dot).
    pub extension: String,
    /// Length of feed moves (G1, G2, G3), mm, from the emitted coordinates.
    pub feed_length_mm: f64,
    /// Length of rapid moves (G0), mm, excluding the leading unmeasured ones.
    pub rapid_length_mm: f64,
    /// Number of G2/G3 blocks.
    pub arc_count: usize,
    /// Number of lines of `text`.
    pub line_count: usize,
    /// Leading motion blocks that start where the machine happens to be
    /// (before the program has set every axis); not in the lengths.
    pub unmeasured_moves: usize,
    /// Number of tool changes written.
    pub tool_changes: usize,
    /// The first line (1-based) of every operation's blocks, in program
    /// order: a checker's line numbers map back to operations by it.
    pub operation_lines: Vec<(usize, OperationId)>,
}

impl NcProgram {
    /// The operation whose blocks hold `line` (1-based), if any.
    pub fn operation_at(&self, line: usize) -> Option<OperationId> {
        let k = self.operation_lines.partition_point(|(l, _)| *l <= line);
        (k > 0).then(|| self.operation_lines[k - 1].1)
    }
}

/// Why a plan cannot be posted. Each names the operation (and move) at fault.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PostError {
    #[error("the plan has no operations to post (run the operations stage first)")]
    NoOperations,
    #[error("the operation order names {0}, which the plan does not have")]
    UnknownOperation(OperationId),
    #[error("the operation order lists {0} twice")]
    RepeatedOperation(OperationId),
    #[error("the operation order leaves out {0}")]
    OmittedOperation(OperationId),
    #[error("the plan's set-up uses tool set `{plan}`, but tool set `{given}` was given")]
    ToolSetMismatch { plan: String, given: String },
    #[error("{operation}: tool `{tool}` is not in tool set `{tool_set}`")]
    UnknownTool {
        operation: OperationId,
        tool: String,
        tool_set: String,
    },
    #[error(
        "{operation}: tool axis ({x}, {y}, {z}) is not +Z; post `{post}` writes 3-axis \
         programs only"
    )]
    ToolAxis {
        operation: OperationId,
        x: f64,
        y: f64,
        z: f64,
        post: String,
    },
    #[error("{operation}: spindle speed {rpm} rpm must be a positive number")]
    Spindle { operation: OperationId, rpm: f64 },
    #[error("{operation}, move {index}: {reason}")]
    Move {
        operation: OperationId,
        /// 0-based index into the operation's moves.
        index: usize,
        reason: String,
    },
    #[error("post `{post}`: {reason}")]
    Template { post: String, reason: String },
}

/// Writes `plan`'s operations (in `plan.operation_order`, or id order when
/// that is empty) as an NC program for `post`, with tool numbers from
/// `tools` (which must be the set-up's tool set).
pub fn post(plan: &Plan, post: &PostProcessor, tools: &ToolSet) -> Result<NcProgram, PostError> {
    if tools.id != plan.setup.tool_set {
        return Err(PostError::ToolSetMismatch {
            plan: plan.setup.tool_set.clone(),
            given: tools.id.clone(),
        });
    }
    let ops = ordered_operations(plan)?;
    for op in &ops {
        check_operation(op, post, tools)?;
    }
    let mut w = Writer::new(post);
    let clearance_z = w.round(highest_point(&ops) + post.clearance);
    let mut vars = program_vars(plan, post, clearance_z);
    let tool_count = ops
        .iter()
        .enumerate()
        .filter(|(i, op)| *i == 0 || ops[i - 1].tool != op.tool)
        .count();
    vars.insert("tool_count", tool_count.to_string());

    w.blocks(&post.header, &vars)?;
    w.blocks(&post.program_start, &vars)?;
    let mut current_tool: Option<&str> = None;
    let mut coolant_on = false;
    let mut last_end: Option<DVec3> = None;
    let mut op_starts = Vec::with_capacity(ops.len());
    for op in &ops {
        let number = tool_number(op, tools)?;
        let tool = &tools.tools[number - 1];
        let mut op_vars = vars.clone();
        op_vars.insert("tool", number.to_string());
        op_vars.insert("tool_id", tool.id.clone());
        op_vars.insert("tool_diameter", w.num(tool.diameter));
        op_vars.insert("rpm", format!("{:.0}", op.spindle_rpm));
        op_vars.insert("operation", op.id.to_string());
        op_vars.insert("feature", op.feature.to_string());
        op_vars.insert("method", op.method.clone());
        let change = current_tool != Some(op.tool.as_str());
        if change {
            // A safe retract before every tool change, the first included.
            w.blocks(&post.safe_retract, &vars)?;
            w.note_retract(clearance_z);
            if current_tool.is_some() {
                w.blocks(&post.spindle_off, &vars)?;
            }
            if coolant_on {
                w.blocks(&post.coolant_off, &vars)?;
                coolant_on = false;
            }
            w.blocks(&post.tool_change, &op_vars)?;
            w.tool_changes += 1;
            current_tool = Some(op.tool.as_str());
        }
        op_starts.push((w.out.len(), op.id));
        w.blocks(&post.operation_start, &op_vars)?;
        w.blocks(&post.spindle_on, &op_vars)?;
        if !coolant_on {
            w.blocks(&post.coolant_on, &vars)?;
            coolant_on = true;
        }
        // Link to the operation's start over the clearance height, unless
        // the previous operation (same tool) ended exactly there, or stage 8
        // planned the link on the in-process stock (straight across at
        // `link_z`, where the previous operation ended).
        let continues = !change && last_end.is_some_and(|e| e.distance(op.start) < 1e-9);
        let planned = op.link_z.filter(|_| !change && last_end.is_some());
        if let (false, Some(z)) = (continues, planned) {
            w.rapid(DVec3::new(f64::NAN, f64::NAN, z));
            w.rapid(DVec3::new(op.start.x, op.start.y, z));
            w.rapid(op.start);
        } else if !continues {
            w.rapid(DVec3::new(f64::NAN, f64::NAN, clearance_z));
            w.rapid(DVec3::new(op.start.x, op.start.y, clearance_z));
            w.rapid(op.start);
        }
        let mut from = op.start;
        for (index, m) in op.moves.iter().enumerate() {
            w.path_move(from, m).map_err(|reason| PostError::Move {
                operation: op.id,
                index,
                reason,
            })?;
            from = m.to;
        }
        last_end = Some(from);
    }
    w.blocks(&post.safe_retract, &vars)?;
    w.note_retract(clearance_z);
    w.blocks(&post.spindle_off, &vars)?;
    if coolant_on {
        w.blocks(&post.coolant_off, &vars)?;
    }
    w.blocks(&post.program_end, &vars)?;
    let line_count = w.out.lines().count();
    let operation_lines = lines_of_offsets(&w.out, &op_starts);
    Ok(NcProgram {
        text: w.out,
        tool_table: tool_table(tools, post.decimals),
        extension: post.extension.clone(),
        feed_length_mm: w.feed_length,
        rapid_length_mm: w.rapid_length,
        arc_count: w.arc_count,
        line_count,
        unmeasured_moves: w.unmeasured,
        tool_changes: w.tool_changes,
        operation_lines,
    })
}

/// 1-based line numbers of byte offsets (ascending) into `text`.
fn lines_of_offsets(text: &str, starts: &[(usize, OperationId)]) -> Vec<(usize, OperationId)> {
    let bytes = text.as_bytes();
    let mut line = 1;
    let mut at = 0;
    starts
        .iter()
        .map(|&(offset, id)| {
            line += bytes[at..offset].iter().filter(|&&b| b == b'\n').count();
            at = offset;
            (line, id)
        })
        .collect()
}

/// The LinuxCNC tool table for a tool set: tool `n` (1-based position in the
/// set) in pocket `n`, its diameter, and no length offset: lengths are
/// measured at the machine, the `Z` column is left for them.
pub fn tool_table(tools: &ToolSet, decimals: u32) -> String {
    let d = decimals as usize;
    let mut s = String::new();
    for (i, t) in tools.tools.iter().enumerate() {
        let n = i + 1;
        let _ = writeln!(
            s,
            "T{n} P{n} D{} Z{} ;{} {:?} r{} ({})",
            number(t.diameter, d),
            number(0.0, d),
            t.id,
            t.kind,
            number(t.corner_radius, d),
            tools.id
        );
    }
    s
}

/// Formats `v` with `decimals` fixed decimals, never as `-0.000`.
pub fn number(v: f64, decimals: usize) -> String {
    let s = format!("{v:.decimals$}");
    match s.strip_prefix('-') {
        Some(rest) if rest.bytes().all(|b| b == b'0' || b == b'.') => rest.to_string(),
        _ => s,
    }
}

/// Points along a circular (or helical) arc, `start` excluded and `end`
/// included, such that no chord is farther than `tolerance` from the arc.
/// The arc turns about `axis` through `centre` (clockwise seen from the tip
/// of `axis` when `clockwise`); an `end` over `start` (seen along the axis)
/// is a full turn. Motion along
/// the axis and any difference of start and end radius are interpolated
/// linearly with the angle.
pub fn linearise_arc(
    start: DVec3,
    end: DVec3,
    centre: DVec3,
    axis: DVec3,
    clockwise: bool,
    tolerance: f64,
) -> Vec<DVec3> {
    let a = axis.normalize();
    let (s, e) = (start - centre, end - centre);
    let (sa, ea) = (s.dot(a), e.dot(a));
    let (sp, ep) = (s - sa * a, e - ea * a);
    let (r0, r1) = (sp.length(), ep.length());
    // Same place seen along the axis: a full turn (a helix if it rises).
    let sweep = signed_sweep(sp, ep, a, clockwise, sp.distance(ep) < 1e-12);
    let r = r0.max(r1);
    // Chord of angle δ on radius r stays within r·(1 − cos(δ/2)) of the arc.
    let step = if tolerance >= r {
        std::f64::consts::PI
    } else {
        2.0 * (1.0 - tolerance / r).acos()
    };
    let n = ((sweep.abs() / step).ceil() as usize).max(1);
    let u0 = if r0 > 0.0 { sp / r0 } else { sp };
    let v0 = a.cross(u0);
    (1..=n)
        .map(|i| {
            if i == n {
                return end;
            }
            let t = i as f64 / n as f64;
            let (sin, cos) = (t * sweep).sin_cos();
            let radius = r0 + t * (r1 - r0);
            centre + (sa + t * (ea - sa)) * a + radius * (cos * u0 + sin * v0)
        })
        .collect()
}

/// The signed angle (positive = counter-clockwise about `a`) from `sp` to
/// `ep`, both normal to `a`, going the given way; a full turn when `full`.
fn signed_sweep(sp: DVec3, ep: DVec3, a: DVec3, clockwise: bool, full: bool) -> f64 {
    let ccw = if full {
        TAU
    } else {
        let mut phi = sp.cross(ep).dot(a).atan2(sp.dot(ep));
        if phi <= 0.0 {
            phi += TAU;
        }
        phi
    };
    if full {
        if clockwise {
            -TAU
        } else {
            TAU
        }
    } else if clockwise {
        ccw - TAU
    } else {
        ccw
    }
}

fn ordered_operations(plan: &Plan) -> Result<Vec<&Operation>, PostError> {
    if plan.operations.is_empty() {
        return Err(PostError::NoOperations);
    }
    let by_id: BTreeMap<OperationId, &Operation> =
        plan.operations.iter().map(|o| (o.id, o)).collect();
    // An order that stage 8 (or the verification, removing every
    // operation) left empty means nothing to cut, not "any order".
    if plan.operation_order.is_empty() && !plan.stages_done.contains(&thinplan_plan::Stage::Order) {
        return Ok(by_id.into_values().collect());
    }
    if plan.operation_order.is_empty() {
        return Err(PostError::NoOperations);
    }
    let mut seen = std::collections::BTreeSet::new();
    let ops = plan
        .operation_order
        .iter()
        .map(|id| {
            if !seen.insert(*id) {
                return Err(PostError::RepeatedOperation(*id));
            }
            by_id
                .get(id)
                .copied()
                .ok_or(PostError::UnknownOperation(*id))
        })
        .collect::<Result<Vec<_>, _>>()?;
    // A partial order would silently drop cutting: refuse it.
    if let Some(id) = by_id.keys().find(|id| !seen.contains(id)) {
        return Err(PostError::OmittedOperation(*id));
    }
    Ok(ops)
}

fn tool_number(op: &Operation, tools: &ToolSet) -> Result<usize, PostError> {
    tools
        .tools
        .iter()
        .position(|t| t.id == op.tool)
        .map(|i| i + 1)
        .ok_or_else(|| PostError::UnknownTool {
            operation: op.id,
            tool: op.tool.clone(),
            tool_set: tools.id.clone(),
        })
}

fn check_operation(op: &Operation, post: &PostProcessor, tools: &ToolSet) -> Result<(), PostError> {
    tool_number(op, tools)?;
    let axis = op.tool_axis.normalize_or_zero();
    if axis.distance(DVec3::Z) > 1e-9 {
        return Err(PostError::ToolAxis {
            operation: op.id,
            x: op.tool_axis.x,
            y: op.tool_axis.y,
            z: op.tool_axis.z,
            post: post.id.clone(),
        });
    }
    if !(op.spindle_rpm.is_finite() && op.spindle_rpm > 0.0) {
        return Err(PostError::Spindle {
            operation: op.id,
            rpm: op.spindle_rpm,
        });
    }
    if !op.start.is_finite() {
        return Err(PostError::Move {
            operation: op.id,
            index: 0,
            reason: "the operation's start point is not finite".into(),
        });
    }
    if op.link_z.is_some_and(|z| !z.is_finite()) {
        return Err(PostError::Move {
            operation: op.id,
            index: 0,
            reason: "the height of its link from the previous operation (link_z) is not finite"
                .into(),
        });
    }
    for (index, m) in op.moves.iter().enumerate() {
        let bad = |reason: &str| PostError::Move {
            operation: op.id,
            index,
            reason: reason.to_string(),
        };
        if !m.to.is_finite() {
            return Err(bad("its end point is not finite"));
        }
        if !(m.feed.is_finite() && m.feed >= 0.0) {
            return Err(bad(&format!(
                "feed {} must be ≥ 0 mm/min (0 for rapid)",
                m.feed
            )));
        }
        if let Some(arc) = &m.arc {
            if !(arc.centre.is_finite() && arc.axis.is_finite()) || arc.axis.length() < 1e-12 {
                return Err(bad(
                    "its arc centre or axis is not a finite, non-zero vector",
                ));
            }
            if m.feed == 0.0 {
                return Err(bad("an arc at rapid (feed 0): arcs are cutting moves"));
            }
        }
    }
    Ok(())
}

/// The highest point any move reaches (arc bulges included).
fn highest_point(ops: &[&Operation]) -> f64 {
    let mut top = f64::NEG_INFINITY;
    for op in ops {
        top = top.max(op.start.z);
        for m in &op.moves {
            top = top.max(m.to.z);
            if let Some(arc) = &m.arc {
                let a = arc.axis.normalize();
                let r = (m.to - arc.centre).reject_from(a).length();
                // An arc about an axis tilted from Z can rise above its ends.
                let rise = r * (1.0 - a.z * a.z).max(0.0).sqrt();
                top = top.max(arc.centre.z + rise);
            }
        }
    }
    top
}

fn program_vars(
    plan: &Plan,
    post: &PostProcessor,
    clearance_z: f64,
) -> BTreeMap<&'static str, String> {
    let d = post.decimals as usize;
    let up = plan.setup.up;
    let mut v = BTreeMap::new();
    v.insert("part", plan.part.source.clone());
    v.insert(
        "sha256",
        plan.part.sha256.chars().take(16).collect::<String>(),
    );
    v.insert(
        "up",
        format!(
            "{} {} {}",
            number(up.x, 3),
            number(up.y, 3),
            number(up.z, 3)
        ),
    );
    v.insert("machine", plan.setup.machine.clone());
    v.insert("tool_set", plan.setup.tool_set.clone());
    v.insert("material", plan.setup.material.clone());
    v.insert(
        "knowledge",
        plan.notes
            .get("knowledge")
            .cloned()
            .unwrap_or_else(|| "(not recorded)".into()),
    );
    v.insert("version", env!("CARGO_PKG_VERSION").to_string());
    v.insert("post", post.id.clone());
    v.insert("post_name", post.name.clone());
    v.insert("work_offset", post.work_offset.clone());
    v.insert("clearance_z", number(clearance_z, d));
    v
}

/// Emits blocks and motion, tracking the emitted (rounded) position.
struct Writer<'a> {
    post: &'a PostProcessor,
    out: String,
    next_line_number: u32,
    /// The emitted position per axis; `None` until the program sets it.
    pos: [Option<f64>; 3],
    /// The last feed word written (rounded).
    feed: Option<f64>,
    feed_length: f64,
    rapid_length: f64,
    arc_count: usize,
    unmeasured: usize,
    tool_changes: usize,
}

impl<'a> Writer<'a> {
    fn new(post: &'a PostProcessor) -> Self {
        Writer {
            post,
            out: String::new(),
            next_line_number: post.line_numbers.start,
            pos: [None; 3],
            feed: None,
            feed_length: 0.0,
            rapid_length: 0.0,
            arc_count: 0,
            unmeasured: 0,
            tool_changes: 0,
        }
    }

    fn decimals(&self) -> usize {
        self.post.decimals as usize
    }

    fn num(&self, v: f64) -> String {
        number(v, self.decimals())
    }

    /// `v` as the controller reads it after formatting.
    fn round(&self, v: f64) -> f64 {
        self.num(v).parse().unwrap_or(v)
    }

    fn code_line(&mut self, text: &str) {
        if self.post.line_numbers.enabled {
            let _ = write!(self.out, "N{} ", self.next_line_number);
            self.next_line_number = self
                .next_line_number
                .saturating_add(self.post.line_numbers.step);
        }
        self.out.push_str(text);
        self.out.push('\n');
    }

    fn comment_line(&mut self, text: &str) {
        let c = &self.post.comments;
        let mut t: String = text
            .chars()
            .map(|ch| match ch {
                // A parenthesis would end or nest an RS274 comment.
                '(' if c.style == CommentStyle::Parentheses => '[',
                ')' if c.style == CommentStyle::Parentheses => ']',
                '\n' | '\r' => ' ',
                ch if c.ascii_only && !(' '..='~').contains(&ch) => '?',
                ch => ch,
            })
            .collect();
        if c.uppercase {
            t = t.to_uppercase();
        }
        match c.style {
            CommentStyle::Parentheses => {
                let _ = writeln!(self.out, "({t})");
            }
            CommentStyle::Semicolon => {
                let _ = writeln!(self.out, "; {t}");
            }
        }
    }

    fn blocks(
        &mut self,
        blocks: &[Block],
        vars: &BTreeMap<&'static str, String>,
    ) -> Result<(), PostError> {
        for b in blocks {
            let text = fill(b.text(), |name| vars.get(name).cloned()).map_err(|reason| {
                PostError::Template {
                    post: self.post.id.clone(),
                    reason,
                }
            })?;
            match b {
                Block::Code(_) => self.code_line(&text),
                Block::Comment(_) => self.comment_line(&text),
                Block::Raw(_) => {
                    self.out.push_str(&text);
                    self.out.push('\n');
                }
            }
        }
        Ok(())
    }

    /// The post's safe retract is one rapid to the clearance height with X
    /// and Y kept (the contract of `safe_retract` templates); measured so.
    fn note_retract(&mut self, clearance_z: f64) {
        let next = [self.pos[0], self.pos[1], Some(clearance_z)];
        self.measure(next, false);
        self.pos = next;
    }

    fn known(&self) -> Option<DVec3> {
        Some(DVec3::new(self.pos[0]?, self.pos[1]?, self.pos[2]?))
    }

    /// Axis words for the axes whose emitted value changes; NaN = keep.
    fn axis_words(&self, to: DVec3, always_xy: bool) -> (String, [Option<f64>; 3]) {
        let mut words = String::new();
        let mut next = self.pos;
        for (i, name) in ['X', 'Y', 'Z'].into_iter().enumerate() {
            if to[i].is_nan() {
                continue;
            }
            let s = self.num(to[i]);
            let v: f64 = s.parse().unwrap_or(to[i]);
            if self.pos[i] != Some(v) || (always_xy && i < 2) {
                let _ = write!(words, " {name}{s}");
                next[i] = Some(v);
            }
        }
        (words, next)
    }

    fn measure(&mut self, next: [Option<f64>; 3], feed: bool) {
        let len = match (self.known(), next) {
            (Some(a), [Some(x), Some(y), Some(z)]) => Some(a.distance(DVec3::new(x, y, z))),
            _ => None,
        };
        match len {
            Some(l) if feed => self.feed_length += l,
            Some(l) => self.rapid_length += l,
            None => self.unmeasured += 1,
        }
    }

    fn rapid(&mut self, to: DVec3) {
        let (words, next) = self.axis_words(to, false);
        if words.is_empty() {
            return;
        }
        self.measure(next, false);
        let line = format!("{}{words}", self.post.motion.rapid);
        self.code_line(&line);
        self.pos = next;
    }

    fn feed_word(&mut self, feed: f64) -> String {
        let d = self.post.feed_decimals as usize;
        let s = number(feed, d);
        let v: f64 = s.parse().unwrap_or(feed);
        if self.feed == Some(v) {
            return String::new();
        }
        self.feed = Some(v);
        format!(" {}{s}", self.post.motion.feed)
    }

    fn linear(&mut self, to: DVec3, feed: f64) {
        let (words, next) = self.axis_words(to, false);
        if words.is_empty() {
            return;
        }
        self.measure(next, true);
        let f = self.feed_word(feed);
        let line = format!("{}{words}{f}", self.post.motion.linear);
        self.code_line(&line);
        self.pos = next;
    }

    /// One move of a tool path, `from` being the exact (unrounded) end of
    /// the previous move.
    fn path_move(&mut self, from: DVec3, m: &PathMove) -> Result<(), String> {
        let Some(arc) = &m.arc else {
            if m.feed == 0.0 {
                self.rapid(m.to);
            } else {
                self.linear(m.to, m.feed);
            }
            return Ok(());
        };
        let a = arc.axis.normalize();
        // Ends at its start seen along the axis: a full turn (or helix turn).
        let full = (m.to - from).reject_from(a).length() < 1e-9;
        let (r0, r1) = (
            (from - arc.centre).reject_from(a).length(),
            (m.to - arc.centre).reject_from(a).length(),
        );
        if (r0 - r1).abs() > 1e-3_f64.max(1e-6 * r0) {
            return Err(format!(
                "the arc's end is not on its circle: radius {r0:.6} at the start, {r1:.6} at \
                 the end"
            ));
        }
        if r0 < 1e-9 {
            return Err("the arc has a zero radius".into());
        }
        let cfg = &self.post.arcs;
        let about_z = a.z.abs() > 1.0 - 1e-9;
        let start = self.known().ok_or("an arc before the position is known")?;
        let dz = self.round(m.to.z) - start.z;
        let as_arc = cfg.enabled
            && about_z
            && (cfg.min_radius..=cfg.max_radius).contains(&r0)
            && (cfg.helical || dz == 0.0);
        if !as_arc {
            let tol = cfg.chord_tolerance;
            for p in linearise_arc(from, m.to, arc.centre, a, arc.clockwise, tol) {
                self.linear(p, m.feed);
            }
            return Ok(());
        }
        // Seen from +Z, an arc about −Z turns the other way.
        let cw_from_above = arc.clockwise == (a.z > 0.0);
        let (xy_words, next) = self.axis_words(m.to, true);
        let end = DVec3::new(next[0].unwrap_or(0.0), next[1].unwrap_or(0.0), start.z + dz);
        if !full && start.truncate() == end.truncate() {
            // Shorter than the output resolution: a G2/G3 here would be read
            // as a full circle.
            self.linear(m.to, m.feed);
            return Ok(());
        }
        let i = self.round(arc.centre.x - start.x);
        let j = self.round(arc.centre.y - start.y);
        let c = DVec2::new(start.x + i, start.y + j);
        let (s2, e2) = (start.truncate() - c, end.truncate() - c);
        let radius = 0.5 * (s2.length() + e2.length());
        let sweep = if full {
            TAU
        } else {
            let mut phi = s2.perp_dot(e2).atan2(s2.dot(e2));
            if cw_from_above {
                phi = -phi;
            }
            if phi <= 0.0 {
                phi += TAU;
            }
            phi
        };
        let length = (radius * sweep).hypot(dz);
        let word = if cw_from_above {
            &self.post.motion.arc_cw
        } else {
            &self.post.motion.arc_ccw
        };
        let f = self.feed_word(m.feed);
        // X Y always (a full circle has no changed axis); Z only for a helix.
        let line = format!("{word}{xy_words} I{} J{}{f}", self.num(i), self.num(j));
        self.code_line(&line);
        self.feed_length += length;
        self.arc_count += 1;
        self.pos = next;
        Ok(())
    }
}
