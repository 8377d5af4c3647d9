//! A small RS274NGC reader for the dialect thinplan's LinuxCNC and Fanuc
//! posts write. It shares no code with the planner or the posts on purpose:
//! the simulation must verify the program text itself.
//!
//! Supported: `%` delimiters, `O` program numbers, `N` words, `( … )` and `;`
//! comments, G0 G1 G2 G3 (modal; arcs in G17 by incremental `I J` centre or by
//! `R`, a negative `R` for the long way round), G17 G20 G21 G40 G43 `H` G49
//! G91.1 (the only arc-centre mode read),
//! G54–G59 G64 [`P` `Q`] G80 G90 G91 G94, `T` M6, M3 M4 M5 `S`, M8 M9, M2 M30,
//! `F`. Everything else is an error naming `file:line:column`.
//!
//! Conventions: coordinates are the tool tip in the part frame (every work
//! offset is taken as the part frame; `G43` is assumed to make Z the tip).
//! Positions are unknown until programmed: the first move of an axis is a
//! positioning move, simulated as coming from above the stock.

use std::fmt;

use glam::{DVec2, DVec3};

/// A reading error at a place in the program text.
#[derive(Debug, Clone, PartialEq)]
pub struct GcodeError {
    pub file: String,
    /// 1-based line.
    pub line: usize,
    /// 1-based column, in characters.
    pub column: usize,
    pub message: String,
}

impl fmt::Display for GcodeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{}:{}:{}: {}",
            self.file, self.line, self.column, self.message
        )
    }
}

impl std::error::Error for GcodeError {}

/// What a move is.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum MoveKind {
    /// G0.
    Rapid,
    /// G1.
    Line,
    /// G2 (`ccw == false`) or G3, in the XY plane, Z moving linearly (helix).
    /// `sweep` is the signed angle turned (positive counter-clockwise), rad.
    Arc {
        center: DVec2,
        ccw: bool,
        sweep: f64,
    },
}

/// Spindle state during a move.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum Spindle {
    Off,
    Cw,
    Ccw,
}

/// One canonical motion, in mm, in the part frame.
#[derive(Debug, Clone, PartialEq)]
pub struct Move {
    /// 1-based line of the block.
    pub line: usize,
    pub kind: MoveKind,
    /// Start point; components are NaN where not yet known (see
    /// [`Move::positioning`]).
    pub start: DVec3,
    pub end: DVec3,
    /// The tool in the spindle (last `T… M6`), if any.
    pub tool: Option<u32>,
    /// Feed rate, mm/min (0 for rapids before any F).
    pub feed: f64,
    pub spindle: Spindle,
}

impl Move {
    /// True when the start is not fully known (the first move of an axis):
    /// the simulation brings the tool in from above and counts no length.
    pub fn positioning(&self) -> bool {
        !(self.start.x.is_finite() && self.start.y.is_finite() && self.start.z.is_finite())
    }

    /// Whether the tool moves at feed (G1/G2/G3).
    pub fn is_feed(&self) -> bool {
        !matches!(self.kind, MoveKind::Rapid)
    }

    /// Path length of the tool tip, mm (0 for positioning moves).
    pub fn length(&self) -> f64 {
        if self.positioning() {
            return 0.0;
        }
        match self.kind {
            MoveKind::Rapid | MoveKind::Line => (self.end - self.start).length(),
            MoveKind::Arc { center, sweep, .. } => {
                let r0 = (self.start.truncate() - center).length();
                let r1 = (self.end.truncate() - center).length();
                let planar = 0.5 * (r0 + r1) * sweep.abs();
                planar.hypot(self.end.z - self.start.z)
            }
        }
    }
}

/// A program read into canonical moves.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Program {
    pub moves: Vec<Move>,
    /// `(line, tool)` for every M6.
    pub tool_changes: Vec<(usize, u32)>,
    /// Things that are legal but worth telling (e.g. `G43 H` not matching the tool).
    pub warnings: Vec<String>,
    /// Whether M2/M30 ended the program.
    pub ended: bool,
}

impl Program {
    /// Feed path length (G1/G2/G3), mm.
    pub fn feed_length(&self) -> f64 {
        self.moves
            .iter()
            .filter(|m| m.is_feed())
            .map(Move::length)
            .sum()
    }

    /// Rapid path length (G0), mm.
    pub fn rapid_length(&self) -> f64 {
        self.moves
            .iter()
            .filter(|m| !m.is_feed())
            .map(Move::length)
            .sum()
    }
}

/// Reads a program from bytes (must be UTF-8).
pub fn parse_bytes(bytes: &[u8], file: &str) -> Result<Program, GcodeError> {
    match std::str::from_utf8(bytes) {
        Ok(text) => parse(text, file),
        Err(e) => {
            let good = &bytes[..e.valid_up_to()];
            let line = 1 + good.iter().filter(|&&b| b == b'\n').count();
            let last = good.iter().rposition(|&b| b == b'\n').map_or(0, |p| p + 1);
            let column = 1 + String::from_utf8_lossy(&good[last..]).chars().count();
            Err(GcodeError {
                file: file.to_string(),
                line,
                column,
                message: "the program is not valid UTF-8 text".into(),
            })
        }
    }
}

/// Reads a program from text.
pub fn parse(text: &str, file: &str) -> Result<Program, GcodeError> {
    let mut m = Machine::new(file);
    let mut percent_seen = false;
    for (i, raw) in text.lines().enumerate() {
        let line_no = i + 1;
        let trimmed = raw.trim();
        if let Some(rest) = trimmed.strip_prefix('%') {
            // `%` opens and closes the program; anything after the closing one is ignored.
            let rest = rest.trim_start();
            if !rest.is_empty() && !rest.starts_with(['(', ';']) {
                let col = 1 + raw.chars().take_while(|c| c.is_whitespace()).count() + 1;
                return Err(m.err(line_no, col, "text after `%` on the same line"));
            }
            if percent_seen || m.ended {
                break;
            }
            percent_seen = true;
            continue;
        }
        if m.ended {
            // Like LinuxCNC, nothing after M2/M30 is read.
            break;
        }
        let block = tokenize(raw, line_no, &m.file)?;
        m.execute(&block, line_no)?;
    }
    Ok(m.finish())
}

/// A word: letter, value, and the column of the letter.
#[derive(Debug, Clone, Copy)]
struct Word {
    letter: char,
    value: f64,
    col: usize,
}

fn tokenize(raw: &str, line: usize, file: &str) -> Result<Vec<Word>, GcodeError> {
    let err = |col: usize, msg: String| GcodeError {
        file: file.to_string(),
        line,
        column: col,
        message: msg,
    };
    let chars: Vec<char> = raw.chars().collect();
    let mut words = Vec::new();
    let mut i = 0;
    while i < chars.len() {
        let c = chars[i];
        let col = i + 1;
        if c.is_whitespace() {
            i += 1;
        } else if c == ';' {
            break;
        } else if c == '(' {
            match chars[i + 1..].iter().position(|&d| d == ')' || d == '(') {
                Some(p) if chars[i + 1 + p] == ')' => i += p + 2,
                Some(p) => {
                    return Err(err(i + 2 + p, "nested comment `(` inside a comment".into()))
                }
                None => return Err(err(col, "comment `(` is not closed on this line".into())),
            }
        } else if c.is_ascii_alphabetic() {
            let letter = c.to_ascii_uppercase();
            i += 1;
            while i < chars.len() && (chars[i] == ' ' || chars[i] == '\t') {
                i += 1;
            }
            let start = i;
            if i < chars.len() && (chars[i] == '+' || chars[i] == '-') {
                i += 1;
            }
            let mut digits = 0;
            let mut dot = false;
            while i < chars.len() && (chars[i].is_ascii_digit() || (chars[i] == '.' && !dot)) {
                if chars[i] == '.' {
                    dot = true;
                } else {
                    digits += 1;
                }
                i += 1;
            }
            if digits == 0 {
                return Err(err(
                    start + 1,
                    format!(
                        "word `{letter}` needs a number (found {})",
                        found(&chars, start)
                    ),
                ));
            }
            let s: String = chars[start..i].iter().collect();
            let value: f64 = s
                .parse()
                .map_err(|_| err(start + 1, format!("bad number `{s}`")))?;
            if !value.is_finite() || value.abs() > 1e9 {
                return Err(err(start + 1, format!("number `{s}` is out of range")));
            }
            words.push(Word { letter, value, col });
        } else {
            return Err(err(
                col,
                format!("unexpected character `{}`", c.escape_default()),
            ));
        }
    }
    Ok(words)
}

fn found(chars: &[char], at: usize) -> String {
    match chars.get(at) {
        Some(c) => format!("`{}`", c.escape_default()),
        None => "the end of the line".into(),
    }
}

/// Modal state of the interpreter.
struct Machine {
    file: String,
    motion: Option<u8>,
    inch: bool,
    incremental: bool,
    pos: DVec3,
    feed: f64,
    spindle: Spindle,
    prepared: Option<u32>,
    tool: Option<u32>,
    ended: bool,
    prog: Program,
}

/// The G codes read, in tenths (G64 = 640).
const G_KNOWN: &[u32] = &[
    0, 10, 20, 30, 170, 200, 210, 400, 430, 490, 540, 550, 560, 570, 580, 590, 640, 800, 900, 910,
    911, 940,
];

fn g_group(g: u32) -> u8 {
    match g {
        0 | 10 | 20 | 30 | 800 => 1,
        170 => 2,
        200 | 210 => 3,
        400 => 4,
        430 | 490 => 5,
        540..=590 => 6,
        640 => 7,
        900 | 910 => 8,
        // G91.1: arc centres I J relative to the start, as this reader always takes them.
        911 => 10,
        _ => 9, // 940
    }
}

fn m_group(m: u32) -> u8 {
    match m {
        3..=5 => 1,
        6 => 2,
        8 | 9 => 3,
        _ => 4, // 2, 30
    }
}

impl Machine {
    fn new(file: &str) -> Self {
        Machine {
            file: file.to_string(),
            motion: None,
            inch: false,
            incremental: false,
            pos: DVec3::splat(f64::NAN),
            feed: 0.0,
            spindle: Spindle::Off,
            prepared: None,
            tool: None,
            ended: false,
            prog: Program::default(),
        }
    }

    fn err(&self, line: usize, column: usize, msg: impl Into<String>) -> GcodeError {
        GcodeError {
            file: self.file.clone(),
            line,
            column,
            message: msg.into(),
        }
    }

    fn finish(self) -> Program {
        self.prog
    }

    fn execute(&mut self, words: &[Word], line: usize) -> Result<(), GcodeError> {
        let mut gs: Vec<(u32, usize)> = Vec::new();
        let mut ms: Vec<(u32, usize)> = Vec::new();
        // X Y Z I J R F S T H P Q N O, at most once each.
        const LETTERS: &str = "XYZIJRFSTHPQNO";
        let mut vals: [Option<Word>; 14] = [None; 14];
        for w in words {
            match w.letter {
                'G' => {
                    let tenths = (w.value * 10.0).round();
                    if (tenths - w.value * 10.0).abs() > 1e-6
                        || !G_KNOWN.contains(&(tenths as u32))
                        || tenths < 0.0
                    {
                        return Err(self.err(
                            line,
                            w.col,
                            format!("G{} is not supported by this reader", fmt_num(w.value)),
                        ));
                    }
                    let g = tenths as u32;
                    if let Some(&(other, _)) = gs.iter().find(|(o, _)| g_group(*o) == g_group(g)) {
                        return Err(self.err(
                            line,
                            w.col,
                            format!(
                                "G{} and G{} are in the same modal group in one block",
                                fmt_num(other as f64 / 10.0),
                                fmt_num(w.value)
                            ),
                        ));
                    }
                    gs.push((g, w.col));
                }
                'M' => {
                    let m = w.value.round();
                    if (m - w.value).abs() > 1e-9
                        || ![2.0, 3.0, 4.0, 5.0, 6.0, 8.0, 9.0, 30.0].contains(&m)
                    {
                        return Err(self.err(
                            line,
                            w.col,
                            format!("M{} is not supported by this reader", fmt_num(w.value)),
                        ));
                    }
                    let m = m as u32;
                    if let Some(&(other, _)) = ms.iter().find(|(o, _)| m_group(*o) == m_group(m)) {
                        return Err(self.err(
                            line,
                            w.col,
                            format!("M{other} and M{m} are in the same modal group in one block"),
                        ));
                    }
                    ms.push((m, w.col));
                }
                c => {
                    let Some(k) = LETTERS.find(c) else {
                        let what = if "ABCUVW".contains(c) {
                            format!("axis `{c}` is not supported (3-axis X Y Z only)")
                        } else if c == 'K' {
                            "`K` is not used in the G17 plane".to_string()
                        } else {
                            format!("word `{c}` is not supported by this reader")
                        };
                        return Err(self.err(line, w.col, what));
                    };
                    if vals[k].is_some() {
                        return Err(self.err(
                            line,
                            w.col,
                            format!("word `{c}` appears twice in one block"),
                        ));
                    }
                    vals[k] = Some(*w);
                }
            }
        }
        let get = |c: char| vals[LETTERS.find(c).unwrap_or(0)];
        let has_g = |g: u32| gs.iter().any(|(x, _)| *x == g);
        let has_m = |m: u32| ms.iter().any(|(x, _)| *x == m);

        if let Some(o) = get('O') {
            let at = words.iter().position(|w| w.letter == 'O').unwrap_or(0);
            let n_first = at == 1 && words[0].letter == 'N';
            if at != 0 && !n_first {
                return Err(self.err(line, o.col, "`O` (program number) must start the line"));
            }
            if words.len() > 1 + usize::from(n_first) {
                return Err(self.err(
                    line,
                    o.col,
                    "`O` (program number) must be alone on its line",
                ));
            }
            return Ok(());
        }
        for c in ['P', 'Q'] {
            if let Some(w) = get(c) {
                if !has_g(640) {
                    return Err(self.err(line, w.col, format!("`{c}` is only read with G64 here")));
                }
            }
        }
        if let Some(w) = get('H') {
            if !has_g(430) {
                return Err(self.err(line, w.col, "`H` without G43"));
            }
        }
        let scale = |inch: bool| if inch { 25.4 } else { 1.0 };

        // RS274NGC order of execution.
        if has_g(200) {
            self.inch = true;
        }
        if has_g(210) {
            self.inch = false;
        }
        if let Some(f) = get('F') {
            if f.value < 0.0 {
                return Err(self.err(line, f.col, "negative feed rate"));
            }
            self.feed = f.value * scale(self.inch);
        }
        if let Some(s) = get('S') {
            if s.value < 0.0 {
                return Err(self.err(line, s.col, "negative spindle speed"));
            }
        }
        if let Some(t) = get('T') {
            if t.value < 0.0 || t.value.fract() != 0.0 {
                return Err(self.err(line, t.col, "tool number must be a whole number ≥ 0"));
            }
            self.prepared = Some(t.value as u32);
        }
        if has_m(6) {
            let col = ms.iter().find(|(m, _)| *m == 6).map_or(1, |x| x.1);
            let Some(t) = self.prepared else {
                return Err(self.err(line, col, "M6 with no tool selected by `T`"));
            };
            self.tool = if t == 0 { None } else { Some(t) };
            self.prog.tool_changes.push((line, t));
        }
        if has_m(3) {
            self.spindle = Spindle::Cw;
        }
        if has_m(4) {
            self.spindle = Spindle::Ccw;
        }
        if has_m(5) {
            self.spindle = Spindle::Off;
        }
        if has_g(430) {
            let h = get('H').map(|w| w.value);
            if let (Some(h), Some(t)) = (h, self.tool) {
                if h != t as f64 {
                    self.prog.warnings.push(format!(
                        "{}:{line}: G43 H{} does not match tool T{t} in the spindle",
                        self.file,
                        fmt_num(h)
                    ));
                }
            }
        }
        if has_g(900) {
            self.incremental = false;
        }
        if has_g(910) {
            self.incremental = true;
        }
        for (g, col) in &gs {
            if matches!(g, 0 | 10 | 20 | 30 | 800) {
                self.motion = Some(*g as u8 / 10);
                if *g == 800 {
                    self.motion = None;
                }
                let _ = col;
            }
        }

        let axes = [get('X'), get('Y'), get('Z')];
        let arc_words = [get('I'), get('J'), get('R')];
        let any_axis = axes.iter().any(Option::is_some);
        let any_arc = arc_words.iter().any(Option::is_some);
        let explicit_motion = gs.iter().find(|(g, _)| matches!(g, 0 | 10 | 20 | 30));
        if any_axis || any_arc {
            let first_col = axes
                .iter()
                .chain(arc_words.iter())
                .flatten()
                .map(|w| w.col)
                .min()
                .or(explicit_motion.map(|x| x.1))
                .unwrap_or(1);
            let Some(motion) = self.motion else {
                return Err(self.err(
                    line,
                    first_col,
                    "coordinates with no motion mode active (G0/G1/G2/G3)",
                ));
            };
            if motion < 2 && any_arc {
                let w = arc_words
                    .iter()
                    .flatten()
                    .next()
                    .map_or(first_col, |w| w.col);
                return Err(self.err(line, w, "`I`/`J`/`R` are only read with G2/G3"));
            }
            let k = scale(self.inch);
            let mut end = self.pos;
            for (a, w) in axes.iter().enumerate() {
                if let Some(w) = w {
                    let v = w.value * k;
                    if self.incremental {
                        if !self.pos[a].is_finite() {
                            return Err(self.err(
                                line,
                                w.col,
                                "incremental (G91) move from a position not yet known",
                            ));
                        }
                        end[a] = self.pos[a] + v;
                    } else {
                        end[a] = v;
                    }
                }
            }
            let start = self.pos;
            if motion >= 1 && self.feed <= 0.0 {
                return Err(self.err(line, first_col, "feed move with no feed rate (`F`)"));
            }
            let kind = match motion {
                0 => MoveKind::Rapid,
                1 => MoveKind::Line,
                _ => self.arc(line, first_col, start, end, motion == 3, arc_words, k)?,
            };
            if start != end || matches!(kind, MoveKind::Arc { .. }) || !start.is_finite() {
                self.prog.moves.push(Move {
                    line,
                    kind,
                    start,
                    end,
                    tool: self.tool,
                    feed: if motion == 0 { 0.0 } else { self.feed },
                    spindle: self.spindle,
                });
            }
            self.pos = end;
        }
        if has_m(2) || has_m(30) {
            self.ended = true;
            self.prog.ended = true;
        }
        Ok(())
    }

    #[allow(clippy::too_many_arguments)]
    fn arc(
        &self,
        line: usize,
        col: usize,
        start: DVec3,
        end: DVec3,
        ccw: bool,
        [i, j, r]: [Option<Word>; 3],
        k: f64,
    ) -> Result<MoveKind, GcodeError> {
        if !(start.x.is_finite() && start.y.is_finite()) {
            return Err(self.err(line, col, "arc from a position not yet known"));
        }
        if !end.is_finite() {
            return Err(self.err(line, col, "arc ends at a position not yet known"));
        }
        let (s, e) = (start.truncate(), end.truncate());
        let center = match r {
            Some(rw) => {
                if i.is_some() || j.is_some() {
                    return Err(self.err(line, rw.col, "an arc takes `R` or `I`/`J`, not both"));
                }
                let rad = rw.value * k;
                let chord = e - s;
                let d = chord.length();
                if d < 1e-9 {
                    return Err(self.err(line, rw.col, "an `R` arc cannot be a full circle"));
                }
                if rad.abs() < 1e-9 {
                    return Err(self.err(line, rw.col, "arc radius is zero"));
                }
                let half = d / 2.0;
                let h2 = rad * rad - half * half;
                if h2 < -(1e-3 + 1e-4 * rad.abs()) * rad.abs() {
                    return Err(self.err(
                        line,
                        rw.col,
                        format!(
                            "arc radius {} is smaller than half the chord {}",
                            fmt_num(rad.abs()),
                            fmt_num(half)
                        ),
                    ));
                }
                let h = h2.max(0.0).sqrt();
                let left = DVec2::new(-chord.y, chord.x) / d;
                // The short arc (R > 0) has its centre on the left for G3, right for G2.
                let side = if ccw == (rad > 0.0) { 1.0 } else { -1.0 };
                (s + e) / 2.0 + left * h * side
            }
            None => {
                if i.is_none() && j.is_none() {
                    return Err(self.err(line, col, "an arc needs `I`/`J` (centre) or `R`"));
                }
                s + DVec2::new(
                    i.map_or(0.0, |w| w.value * k),
                    j.map_or(0.0, |w| w.value * k),
                )
            }
        };
        let r0 = (s - center).length();
        let r1 = (e - center).length();
        if r0 < 1e-6 {
            return Err(self.err(line, col, "arc radius is zero"));
        }
        if (r0 - r1).abs() > 0.005f64.max(0.001 * r0) {
            return Err(self.err(
                line,
                col,
                format!(
                    "arc radius to the end ({}) differs from the radius to the start ({})",
                    fmt_num(r1),
                    fmt_num(r0)
                ),
            ));
        }
        let a0 = (s - center).to_angle();
        let a1 = (e - center).to_angle();
        let tau = std::f64::consts::TAU;
        let mut sweep = if ccw { a1 - a0 } else { a0 - a1 };
        sweep = sweep.rem_euclid(tau);
        if sweep < 1e-9 {
            sweep = tau; // start == end: a full circle
        }
        Ok(MoveKind::Arc {
            center,
            ccw,
            sweep: if ccw { sweep } else { -sweep },
        })
    }
}

fn fmt_num(v: f64) -> String {
    let s = format!("{v:.4}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    s.to_string()
}
