//! Value checks with a place in the file.
//!
//! Serde gives the loader typed values but no spans for them, so a value
//! check records *where* the value lives as a path of field names and list
//! indices ([`Seg`]); [`locate`] finds that path in the file's text with a
//! small, lenient reader of RON's structure (comments, strings, groups,
//! `name: value` fields) and gives the value's line and column, so a range
//! error points at the number as a syntax error does.

use std::fmt;

/// One step of a path to a value: a field by name or an element by index
/// (of a list or a tuple). Wrappers written around a value (`Some(…)`, an
/// enum variant's name and parentheses) are looked through.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Seg {
    Field(&'static str),
    Index(usize),
}

impl From<&'static str> for Seg {
    fn from(f: &'static str) -> Self {
        Seg::Field(f)
    }
}

impl From<usize> for Seg {
    fn from(i: usize) -> Self {
        Seg::Index(i)
    }
}

/// A path of [`Seg`]s: `at!["tools", 3, "flutes"]`.
#[macro_export]
macro_rules! at {
    ($($s:expr),* $(,)?) => { vec![$($crate::check::Seg::from($s)),*] };
}

/// One problem with a value: where it is in its file and what is wrong.
#[derive(Debug, Clone, PartialEq)]
pub struct Problem {
    pub at: Vec<Seg>,
    pub message: String,
}

/// An allowed range of a number: its bounds and whether each is included.
/// Every range is finite-only: NaN and ±∞ are always outside.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Range {
    pub lo: f64,
    pub lo_incl: bool,
    pub hi: f64,
    pub hi_incl: bool,
}

impl Range {
    /// `[lo, hi]`.
    pub const fn closed(lo: f64, hi: f64) -> Range {
        Range {
            lo,
            lo_incl: true,
            hi,
            hi_incl: true,
        }
    }
    /// `(lo, hi]`.
    pub const fn above(lo: f64, hi: f64) -> Range {
        Range {
            lo,
            lo_incl: false,
            hi,
            hi_incl: true,
        }
    }
    /// `[lo, hi)`.
    pub const fn below(lo: f64, hi: f64) -> Range {
        Range {
            lo,
            lo_incl: true,
            hi,
            hi_incl: false,
        }
    }
    /// `(lo, hi)`.
    pub const fn open(lo: f64, hi: f64) -> Range {
        Range {
            lo,
            lo_incl: false,
            hi,
            hi_incl: false,
        }
    }
    /// `(0, ∞)`: any positive finite number.
    pub const POSITIVE: Range = Range::open(0.0, f64::INFINITY);
    /// `[0, ∞)`: zero or any positive finite number.
    pub const NON_NEGATIVE: Range = Range::below(0.0, f64::INFINITY);

    pub fn contains(&self, v: f64) -> bool {
        v.is_finite()
            && (if self.lo_incl {
                v >= self.lo
            } else {
                v > self.lo
            })
            && (if self.hi_incl {
                v <= self.hi
            } else {
                v < self.hi
            })
    }
}

impl fmt::Display for Range {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let hi = if self.hi.is_infinite() {
            "∞".to_string()
        } else {
            self.hi.to_string()
        };
        write!(
            f,
            "{}{}, {hi}{}",
            if self.lo_incl { '[' } else { '(' },
            self.lo,
            if self.hi_incl && self.hi.is_finite() {
                ']'
            } else {
                ')'
            }
        )
    }
}

/// Collects problems; `prefix` names the entity ("tool `em12` in set …: ").
#[derive(Debug, Default)]
pub struct Checks {
    pub out: Vec<Problem>,
}

impl Checks {
    /// A problem at `at`.
    pub fn push(&mut self, at: Vec<Seg>, message: String) {
        self.out.push(Problem { at, message });
    }

    /// `v` must lie in `r`: "{prefix}{name} {v} must lie in {r}{why}".
    pub fn range(&mut self, at: Vec<Seg>, prefix: &str, name: &str, v: f64, r: Range, why: &str) {
        if !r.contains(v) {
            self.push(at, format!("{prefix}{name} {v} must lie in {r}{why}"));
        }
    }

    /// A whole number `v` must lie in `lo..=hi`.
    pub fn count(&mut self, at: Vec<Seg>, prefix: &str, name: &str, v: u32, lo: u32, hi: u32) {
        if !(lo..=hi).contains(&v) {
            self.push(at, format!("{prefix}{name} {v} must lie in {lo}..={hi}"));
        }
    }

    /// The messages alone (the `problems()` of each knowledge type).
    pub fn messages(self) -> Vec<String> {
        self.out.into_iter().map(|p| p.message).collect()
    }
}

/// One value in the text: where it starts and, for groups, what it holds.
#[derive(Debug)]
struct Node {
    start: usize,
    /// `(…)` or `[…]` / `{…}` contents; `None` for a scalar.
    items: Option<Vec<(Option<String>, Node)>>,
    /// Whether the group is a list (`[…]` or `{…}`), not parentheses.
    list: bool,
}

#[derive(Debug, Clone, PartialEq)]
enum Tok {
    Open(u8),
    Close,
    Comma,
    Colon,
    Word(String),
    Str,
}

/// Splits RON text into tokens with their byte offsets. Lenient: anything
/// unexpected becomes a word; never panics.
fn tokens(text: &str) -> Vec<(usize, Tok)> {
    let b = text.as_bytes();
    let mut out = Vec::new();
    let mut i = 0;
    while i < b.len() {
        let c = b[i];
        match c {
            b' ' | b'\t' | b'\r' | b'\n' => i += 1,
            b'/' if b.get(i + 1) == Some(&b'/') => {
                while i < b.len() && b[i] != b'\n' {
                    i += 1;
                }
            }
            b'/' if b.get(i + 1) == Some(&b'*') => {
                // RON block comments nest.
                let mut depth = 0usize;
                while i < b.len() {
                    if b[i] == b'/' && b.get(i + 1) == Some(&b'*') {
                        depth += 1;
                        i += 2;
                    } else if b[i] == b'*' && b.get(i + 1) == Some(&b'/') {
                        depth -= 1;
                        i += 2;
                        if depth == 0 {
                            break;
                        }
                    } else {
                        i += 1;
                    }
                }
            }
            b'(' | b'[' | b'{' => {
                out.push((i, Tok::Open(c)));
                i += 1;
            }
            b')' | b']' | b'}' => {
                out.push((i, Tok::Close));
                i += 1;
            }
            b',' => {
                out.push((i, Tok::Comma));
                i += 1;
            }
            b':' => {
                out.push((i, Tok::Colon));
                i += 1;
            }
            b'"' | b'\'' => {
                let start = i;
                i += 1;
                while i < b.len() && b[i] != c {
                    i += if b[i] == b'\\' { 2 } else { 1 };
                }
                i += 1;
                out.push((start, Tok::Str));
            }
            b'r' if matches!(b.get(i + 1), Some(b'"') | Some(b'#')) => {
                // A raw string r#"…"#: ends at `"` followed by as many `#`.
                let start = i;
                i += 1;
                let mut hashes = 0;
                while b.get(i) == Some(&b'#') {
                    hashes += 1;
                    i += 1;
                }
                if b.get(i) != Some(&b'"') {
                    // `r#ident`: a raw identifier.
                    let s = i;
                    while i < b.len() && is_word(b[i]) {
                        i += 1;
                    }
                    out.push((start, Tok::Word(text[s..i].to_string())));
                    continue;
                }
                i += 1;
                loop {
                    if i >= b.len() {
                        break;
                    }
                    if b[i] == b'"' && b[i + 1..].iter().take(hashes).all(|h| *h == b'#') {
                        i += 1 + hashes;
                        break;
                    }
                    i += 1;
                }
                out.push((start, Tok::Str));
            }
            _ => {
                let start = i;
                while i < b.len() && is_word(b[i]) {
                    i += 1;
                }
                if i == start {
                    i += 1;
                }
                out.push((start, Tok::Word(text[start..i].to_string())));
            }
        }
    }
    out
}

fn is_word(c: u8) -> bool {
    !matches!(
        c,
        b' ' | b'\t'
            | b'\r'
            | b'\n'
            | b'('
            | b')'
            | b'['
            | b']'
            | b'{'
            | b'}'
            | b','
            | b':'
            | b'"'
            | b'\''
            | b'/'
    )
}

struct Reader {
    toks: Vec<(usize, Tok)>,
    pos: usize,
    /// Nesting guard: hostile text ends the read, not the stack.
    depth: usize,
}

impl Reader {
    fn peek(&self) -> Option<&Tok> {
        self.toks.get(self.pos).map(|(_, t)| t)
    }

    fn offset(&self) -> usize {
        self.toks.get(self.pos).map_or(0, |(o, _)| *o)
    }

    /// One value: a word or string, optionally followed by a group (a
    /// variant or struct name), or a bare group.
    fn value(&mut self) -> Node {
        let start = self.offset();
        let mut node = Node {
            start,
            items: None,
            list: false,
        };
        if matches!(self.peek(), Some(Tok::Word(_)) | Some(Tok::Str)) {
            self.pos += 1;
        }
        if let Some(Tok::Open(c)) = self.peek() {
            let c = *c;
            self.pos += 1;
            node.list = c != b'(';
            node.items = Some(self.group());
        }
        node
    }

    /// The items of a group up to its closing bracket.
    fn group(&mut self) -> Vec<(Option<String>, Node)> {
        let mut items = Vec::new();
        self.depth += 1;
        if self.depth > 256 {
            self.pos = self.toks.len();
            return items;
        }
        loop {
            match self.peek() {
                None => break,
                Some(Tok::Close) => {
                    self.pos += 1;
                    break;
                }
                Some(Tok::Comma) | Some(Tok::Colon) => self.pos += 1,
                _ => {
                    let named = match (self.peek(), self.toks.get(self.pos + 1)) {
                        (Some(Tok::Word(w)), Some((_, Tok::Colon))) => Some(w.clone()),
                        _ => None,
                    };
                    if named.is_some() {
                        self.pos += 2;
                    }
                    let before = self.pos;
                    let v = self.value();
                    if self.pos == before {
                        self.pos += 1;
                    }
                    items.push((named, v));
                }
            }
        }
        self.depth -= 1;
        items
    }
}

/// Looks through wrappers with exactly one unnamed item (`Some(x)`,
/// `Variant(x)`) once.
fn unwrap_one(n: &Node) -> Option<&Node> {
    match &n.items {
        Some(items) if !n.list && items.len() == 1 && items[0].0.is_none() => Some(&items[0].1),
        _ => None,
    }
}

fn step(n: &Node, s: Seg) -> Option<&Node> {
    let mut cur = n;
    for _ in 0..16 {
        let items = cur.items.as_ref()?;
        match s {
            Seg::Field(f) => {
                if let Some((_, v)) = items.iter().find(|(k, _)| k.as_deref() == Some(f)) {
                    return Some(v);
                }
            }
            Seg::Index(i) => {
                if cur.list || items.len() > 1 {
                    return items.get(i).map(|(_, v)| v);
                }
            }
        }
        let inner = unwrap_one(cur)?;
        if inner.items.is_none() {
            // `Some(5.0)` read as a one-element tuple.
            return (s == Seg::Index(0)).then_some(inner);
        }
        cur = inner;
    }
    None
}

/// The 1-based line and column (in characters) of the value at `at` in
/// `text`, or of the nearest enclosing value found, or (1, 1).
pub fn locate(text: &str, at: &[Seg]) -> (usize, usize, usize) {
    let mut r = Reader {
        toks: tokens(text),
        pos: 0,
        depth: 0,
    };
    let root = r.value();
    let mut node = &root;
    for s in at {
        match step(node, *s) {
            Some(n) => node = n,
            None => break,
        }
    }
    let offset = node.start.min(text.len());
    let before = &text[..floor_char_boundary(text, offset)];
    let line = before.matches('\n').count() + 1;
    let col = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
    (line, col, offset)
}

fn floor_char_boundary(text: &str, mut i: usize) -> usize {
    while i > 0 && !text.is_char_boundary(i) {
        i -= 1;
    }
    i
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finds_fields_through_wrappers_lists_and_comments() {
        let text = "// c (not: 1)\n(\n    tools: [\n        (id: \"a\", d: 1.0),\n        ( id: \"b(\", /* x: 2 */ d: 2.0 ),\n    ],\n    b: Some((s: 0.5)),\n    e: Ramp(angle: 3.0),\n    t: (0.0, 40.0),\n    w: [X((id: \"q\", v: 7))],\n)\n";
        let lc = |at: Vec<Seg>| {
            let (l, c, _) = locate(text, &at);
            (l, c)
        };
        assert_eq!(lc(at!["tools", 1, "d"]), (5, 35));
        assert_eq!(lc(at!["tools", 0, "d"]).0, 4);
        assert_eq!(lc(at!["b", "s"]), (7, 17));
        assert_eq!(lc(at!["e", "angle"]), (8, 20));
        assert_eq!(lc(at!["t", 1]), (9, 14));
        assert_eq!(lc(at!["w", 0, "v"]), (10, 24));
        // Not found: the nearest enclosing value.
        assert_eq!(lc(at!["tools", 1, "zz"]).0, 5);
        assert_eq!(lc(at!["nope"]), (2, 1));
        let (l, c, _) = locate("", &[Seg::Field("x")]);
        assert_eq!((l, c), (1, 1));
    }
}
