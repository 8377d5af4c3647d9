//! ISO 10303-21 ("Part 21") exchange structure parser.
//!
//! Hand-written and byte-oriented. The whole file is parsed into flat arenas:
//! every parameter is a [`Value`] in one vector, lists are ranges into it, and
//! strings, enumerations and keywords are byte spans into the source, decoded
//! only on demand. Nothing recurses on the machine stack: nesting is handled
//! with an explicit stack bounded by [`ParseLimits::max_depth`].

use std::borrow::Cow;
use std::collections::HashMap;

/// Bounds that make hostile input end in an error instead of a hang or an
/// exhausted stack.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ParseLimits {
    pub max_bytes: usize,
    pub max_entities: usize,
    pub max_depth: usize,
}

/// A byte range in the source.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Span {
    pub start: u32,
    pub len: u32,
}

impl Span {
    fn range(self) -> std::ops::Range<usize> {
        self.start as usize..self.start as usize + self.len as usize
    }
}

/// A range of values in [`Exchange::values`]: the elements of one list.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct ListRange {
    pub start: u32,
    pub len: u32,
}

/// One parameter.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Value {
    /// `#12`
    Ref(u64),
    Int(i64),
    Real(f64),
    /// A string, raw (between the quotes, `''` and `\X2\` not yet decoded).
    Str(Span),
    /// An enumeration `.T.`, without the dots.
    Enum(Span),
    /// A binary `"0FF"`, without the quotes.
    Binary(Span),
    /// `$`
    Null,
    /// `*`
    Derived,
    List(ListRange),
    /// A typed parameter `LENGTH_MEASURE(1.)`.
    Typed {
        name: Span,
        args: ListRange,
    },
}

/// One partial record: a type name and its parameters. A simple entity has
/// one, a complex entity `(A(..) B(..))` several.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Part {
    pub name: Span,
    pub args: ListRange,
}

/// An entity instance `#id = ...;`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Entity {
    pub id: u64,
    /// Byte offset of the `#` that starts it (see [`Exchange::line_col`]).
    pub offset: u32,
    pub parts_start: u32,
    pub parts_len: u16,
    pub complex: bool,
}

/// A syntax or limit error with its place.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ParseError {
    pub line: usize,
    pub column: usize,
    pub reason: String,
    /// True when a [`ParseLimits`] bound was hit rather than bad syntax.
    pub limit: bool,
}

impl std::fmt::Display for ParseError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "line {}, column {}: {}",
            self.line, self.column, self.reason
        )
    }
}

impl std::error::Error for ParseError {}

enum Index {
    Dense(Vec<u32>),
    Sparse(HashMap<u64, u32>),
}

const NONE: u32 = u32::MAX;

/// A parsed exchange structure.
pub struct Exchange<'a> {
    pub src: &'a [u8],
    /// Header records (`FILE_DESCRIPTION`, `FILE_NAME`, `FILE_SCHEMA` …).
    pub header: Vec<Part>,
    pub entities: Vec<Entity>,
    pub parts: Vec<Part>,
    pub values: Vec<Value>,
    /// Non-fatal oddities met while parsing.
    pub warnings: Vec<String>,
    index: Index,
}

impl std::fmt::Debug for Exchange<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Exchange")
            .field("bytes", &self.src.len())
            .field("header", &self.header.len())
            .field("entities", &self.entities.len())
            .field("values", &self.values.len())
            .field("warnings", &self.warnings)
            .finish()
    }
}

impl<'a> Exchange<'a> {
    /// The position of the entity with this id in [`Exchange::entities`].
    pub fn index_of(&self, id: u64) -> Option<usize> {
        let i = match &self.index {
            Index::Dense(v) => *v.get(usize::try_from(id).ok()?)?,
            Index::Sparse(m) => *m.get(&id)?,
        };
        (i != NONE).then_some(i as usize)
    }

    pub fn get(&self, id: u64) -> Option<&Entity> {
        self.index_of(id).and_then(|i| self.entities.get(i))
    }

    pub fn parts_of(&self, e: &Entity) -> &[Part] {
        let s = e.parts_start as usize;
        self.parts.get(s..s + e.parts_len as usize).unwrap_or(&[])
    }

    /// The part of an entity with the given type name, if any.
    pub fn part(&self, e: &Entity, name: &str) -> Option<&Part> {
        self.parts_of(e).iter().find(|p| self.name(p.name) == name)
    }

    /// A keyword (type name). Keywords are ASCII by construction.
    pub fn name(&self, s: Span) -> &str {
        self.src
            .get(s.range())
            .and_then(|b| std::str::from_utf8(b).ok())
            .unwrap_or("")
    }

    pub fn raw(&self, s: Span) -> &[u8] {
        self.src.get(s.range()).unwrap_or(&[])
    }

    pub fn list(&self, r: ListRange) -> &[Value] {
        let s = r.start as usize;
        self.values.get(s..s + r.len as usize).unwrap_or(&[])
    }

    pub fn args(&self, p: &Part) -> &[Value] {
        self.list(p.args)
    }

    /// A string parameter, decoded (`''`, `\\`, `\S\`, `\X\`, `\X2\`, `\X4\`).
    pub fn string(&self, s: Span) -> Cow<'a, str> {
        let src: &'a [u8] = self.src;
        decode_string(src.get(s.range()).unwrap_or(&[]))
    }

    /// 1-based line and column of a byte offset.
    pub fn line_col(&self, offset: usize) -> (usize, usize) {
        line_col(self.src, offset)
    }

    /// The schema named by `FILE_SCHEMA`, or empty.
    pub fn schema(&self) -> String {
        for h in &self.header {
            if self.name(h.name) == "FILE_SCHEMA" {
                if let Some(Value::List(l)) = self.args(h).first() {
                    let names: Vec<String> = self
                        .list(*l)
                        .iter()
                        .filter_map(|v| match v {
                            Value::Str(s) => Some(self.string(*s).into_owned()),
                            _ => None,
                        })
                        .collect();
                    return names.join(", ");
                }
            }
        }
        String::new()
    }
}

/// 1-based line and column of a byte offset in `src`.
pub fn line_col(src: &[u8], offset: usize) -> (usize, usize) {
    let end = offset.min(src.len());
    let before = &src[..end];
    let line = 1 + before.iter().filter(|&&b| b == b'\n').count();
    let col = match before.iter().rposition(|&b| b == b'\n') {
        Some(p) => end - p,
        None => end + 1,
    };
    (line, col)
}

/// Decodes a raw Part 21 string (the bytes between the quotes).
pub fn decode_string(raw: &[u8]) -> Cow<'_, str> {
    if !raw.iter().any(|&b| b == b'\'' || b == b'\\' || b >= 0x80) {
        // Pure ASCII without escapes.
        return Cow::Borrowed(std::str::from_utf8(raw).unwrap_or(""));
    }
    let mut out = String::with_capacity(raw.len());
    let mut i = 0;
    let hex = |b: &[u8]| -> Option<u32> {
        let s = std::str::from_utf8(b).ok()?;
        u32::from_str_radix(s, 16).ok()
    };
    while i < raw.len() {
        let b = raw[i];
        if b == b'\'' {
            out.push('\'');
            i += if raw.get(i + 1) == Some(&b'\'') { 2 } else { 1 };
        } else if b == b'\\' {
            let rest = &raw[i..];
            if rest.starts_with(b"\\\\") {
                out.push('\\');
                i += 2;
            } else if rest.starts_with(b"\\S\\") && rest.len() >= 4 {
                out.push(char::from(rest[3].wrapping_add(128)));
                i += 4;
            } else if rest.starts_with(b"\\P") && rest.len() >= 4 && rest[3] == b'\\' {
                i += 4; // code page selection: ignored
            } else if rest.starts_with(b"\\X\\") && rest.len() >= 5 {
                match hex(&rest[3..5]).and_then(char::from_u32) {
                    Some(c) => out.push(c),
                    None => out.push(char::REPLACEMENT_CHARACTER),
                }
                i += 5;
            } else if rest.starts_with(b"\\X2\\") || rest.starts_with(b"\\X4\\") {
                let width = if rest[2] == b'2' { 4 } else { 8 };
                let body_end = rest[4..]
                    .windows(4)
                    .position(|w| w == b"\\X0\\")
                    .map(|p| p + 4)
                    .unwrap_or(rest.len());
                let body = &rest[4..body_end];
                let units: Vec<u32> = body.chunks(width).filter_map(hex).collect();
                if width == 4 {
                    let u16s: Vec<u16> = units.iter().map(|&u| u as u16).collect();
                    out.extend(
                        char::decode_utf16(u16s).map(|c| c.unwrap_or(char::REPLACEMENT_CHARACTER)),
                    );
                } else {
                    out.extend(
                        units
                            .iter()
                            .map(|&u| char::from_u32(u).unwrap_or(char::REPLACEMENT_CHARACTER)),
                    );
                }
                i += (body_end + 4).min(rest.len());
            } else {
                out.push('\\');
                i += 1;
            }
        } else if b < 0x80 {
            out.push(char::from(b));
            i += 1;
        } else {
            // Not valid Part 21; accept UTF-8 if it is, else Latin-1.
            let end = raw[i..]
                .iter()
                .position(|&c| c < 0x80)
                .map(|p| i + p)
                .unwrap_or(raw.len());
            match std::str::from_utf8(&raw[i..end]) {
                Ok(s) => out.push_str(s),
                Err(_) => out.extend(raw[i..end].iter().map(|&c| char::from(c))),
            }
            i = end;
        }
    }
    Cow::Owned(out)
}

struct Parser<'a> {
    src: &'a [u8],
    pos: usize,
    limits: ParseLimits,
    values: Vec<Value>,
    scratch: Vec<Value>,
    parts: Vec<Part>,
    entities: Vec<Entity>,
    header: Vec<Part>,
    warnings: Vec<String>,
    stack: Vec<(usize, Option<Span>)>,
}

type PResult<T> = Result<T, ParseError>;

fn is_kw_start(b: u8) -> bool {
    b.is_ascii_alphabetic() || b == b'_' || b == b'!'
}

fn is_kw(b: u8) -> bool {
    b.is_ascii_alphanumeric() || b == b'_' || b == b'-'
}

/// Parses a whole exchange structure.
pub fn parse(src: &[u8], limits: ParseLimits) -> Result<Exchange<'_>, ParseError> {
    if src.len() > limits.max_bytes {
        return Err(ParseError {
            line: 1,
            column: 1,
            reason: format!(
                "file is {} bytes, more than the limit of {} bytes",
                src.len(),
                limits.max_bytes
            ),
            limit: true,
        });
    }
    if src.len() >= u32::MAX as usize {
        return Err(ParseError {
            line: 1,
            column: 1,
            reason: "file larger than 4 GiB".into(),
            limit: true,
        });
    }
    let mut p = Parser {
        src,
        pos: 0,
        limits,
        values: Vec::with_capacity(src.len() / 12),
        scratch: Vec::with_capacity(256),
        parts: Vec::with_capacity(src.len() / 48),
        entities: Vec::with_capacity(src.len() / 48),
        header: Vec::new(),
        warnings: Vec::new(),
        stack: Vec::with_capacity(16),
    };
    p.file()?;
    let index = build_index(&p.entities, src)?;
    Ok(Exchange {
        src,
        header: p.header,
        entities: p.entities,
        parts: p.parts,
        values: p.values,
        warnings: p.warnings,
        index,
    })
}

fn build_index(entities: &[Entity], src: &[u8]) -> PResult<Index> {
    let max_id = entities.iter().map(|e| e.id).max().unwrap_or(0);
    let dup = |e: &Entity, first: u32| {
        let (line, column) = line_col(src, e.offset as usize);
        let (fl, _) = line_col(src, first as usize);
        ParseError {
            line,
            column,
            reason: format!("duplicate entity #{} (first defined on line {})", e.id, fl),
            limit: false,
        }
    };
    if max_id <= (entities.len() as u64).saturating_mul(4) + 1024 {
        let mut v = vec![NONE; max_id as usize + 1];
        for (i, e) in entities.iter().enumerate() {
            let slot = &mut v[e.id as usize];
            if *slot != NONE {
                return Err(dup(e, entities[*slot as usize].offset));
            }
            *slot = i as u32;
        }
        Ok(Index::Dense(v))
    } else {
        let mut m = HashMap::with_capacity(entities.len());
        for (i, e) in entities.iter().enumerate() {
            if let Some(&prev) = m.get(&e.id) {
                return Err(dup(e, entities[prev as usize].offset));
            }
            m.insert(e.id, i as u32);
        }
        Ok(Index::Sparse(m))
    }
}

impl<'a> Parser<'a> {
    fn err_at(&self, pos: usize, reason: impl Into<String>) -> ParseError {
        let (line, column) = line_col(self.src, pos);
        ParseError {
            line,
            column,
            reason: reason.into(),
            limit: false,
        }
    }

    fn err(&self, reason: impl Into<String>) -> ParseError {
        self.err_at(self.pos, reason)
    }

    fn limit_err(&self, reason: impl Into<String>) -> ParseError {
        let mut e = self.err(reason);
        e.limit = true;
        e
    }

    fn unexpected(&self, expected: &str) -> ParseError {
        match self.src.get(self.pos) {
            None => self.err(format!("unexpected end of file, expected {expected}")),
            Some(&b) if b.is_ascii_graphic() => self.err(format!(
                "unexpected '{}', expected {expected}",
                char::from(b)
            )),
            Some(&b) => self.err(format!("unexpected byte 0x{b:02X}, expected {expected}")),
        }
    }

    /// Skips whitespace and comments.
    #[inline]
    fn ws(&mut self) -> PResult<()> {
        loop {
            match self.src.get(self.pos) {
                Some(b' ' | b'\n' | b'\r' | b'\t' | 0x0B | 0x0C) => self.pos += 1,
                Some(b'/') if self.src.get(self.pos + 1) == Some(&b'*') => {
                    let start = self.pos;
                    match self.src[self.pos + 2..].windows(2).position(|w| w == b"*/") {
                        Some(p) => self.pos += 2 + p + 2,
                        None => return Err(self.err_at(start, "unterminated comment")),
                    }
                }
                _ => return Ok(()),
            }
        }
    }

    fn peek(&self) -> Option<u8> {
        self.src.get(self.pos).copied()
    }

    fn expect(&mut self, b: u8, what: &str) -> PResult<()> {
        self.ws()?;
        if self.peek() == Some(b) {
            self.pos += 1;
            Ok(())
        } else {
            Err(self.unexpected(what))
        }
    }

    fn keyword(&mut self) -> PResult<Span> {
        let start = self.pos;
        match self.peek() {
            Some(b) if is_kw_start(b) => self.pos += 1,
            _ => return Err(self.unexpected("a keyword")),
        }
        while let Some(b) = self.peek() {
            if is_kw(b) {
                self.pos += 1;
            } else {
                break;
            }
        }
        Ok(Span {
            start: start as u32,
            len: (self.pos - start) as u32,
        })
    }

    fn word_is(&self, s: Span, w: &[u8]) -> bool {
        &self.src[s.range()] == w
    }

    fn file(&mut self) -> PResult<()> {
        // Tolerate a UTF-8 byte order mark.
        if self.src.starts_with(&[0xEF, 0xBB, 0xBF]) {
            self.pos = 3;
        }
        self.ws()?;
        let kw = self.keyword()?;
        if !self.word_is(kw, b"ISO-10303-21") {
            return Err(self.err_at(kw.start as usize, "expected ISO-10303-21; at the start"));
        }
        self.expect(b';', "';'")?;
        let mut seen_data = false;
        loop {
            self.ws()?;
            if self.pos >= self.src.len() {
                if seen_data {
                    self.warnings
                        .push("missing END-ISO-10303-21; at the end of the file".into());
                    return Ok(());
                }
                return Err(self.err("unexpected end of file, expected a DATA section"));
            }
            let start = self.pos;
            let kw = self.keyword()?;
            let word = &self.src[kw.range()];
            match word {
                b"END-ISO-10303-21" => {
                    self.expect(b';', "';'")?;
                    if !seen_data {
                        return Err(self.err_at(start, "no DATA section"));
                    }
                    return Ok(());
                }
                b"HEADER" => {
                    self.expect(b';', "';'")?;
                    self.header_section()?;
                }
                b"DATA" => {
                    self.ws()?;
                    if self.peek() == Some(b'(') {
                        // Edition 3: DATA('name', ('schema'));
                        self.params()?;
                    }
                    self.expect(b';', "';'")?;
                    self.data_section()?;
                    seen_data = true;
                }
                b"ANCHOR" | b"REFERENCE" | b"SIGNATURE" => {
                    self.expect(b';', "';'")?;
                    self.skip_section()?;
                }
                _ => {
                    return Err(self.err_at(
                        start,
                        format!(
                            "unexpected section keyword {}",
                            String::from_utf8_lossy(word)
                        ),
                    ))
                }
            }
        }
    }

    fn is_endsec(&mut self) -> PResult<bool> {
        self.ws()?;
        if self.src[self.pos..].starts_with(b"ENDSEC")
            && !self.src.get(self.pos + 6).is_some_and(|&b| is_kw(b))
        {
            self.pos += 6;
            self.expect(b';', "';' after ENDSEC")?;
            return Ok(true);
        }
        Ok(false)
    }

    fn header_section(&mut self) -> PResult<()> {
        loop {
            if self.is_endsec()? {
                return Ok(());
            }
            let name = self.keyword()?;
            let args = self.params()?;
            self.expect(b';', "';'")?;
            self.header.push(Part { name, args });
        }
    }

    fn skip_section(&mut self) -> PResult<()> {
        // Token-wise skip so that strings containing ENDSEC do not confuse us.
        loop {
            if self.is_endsec()? {
                return Ok(());
            }
            match self.peek() {
                None => return Err(self.err("unexpected end of file in a section")),
                Some(b'\'') => {
                    self.string()?;
                }
                Some(_) => self.pos += 1,
            }
        }
    }

    fn data_section(&mut self) -> PResult<()> {
        loop {
            if self.is_endsec()? {
                return Ok(());
            }
            let start = self.pos;
            if self.peek() != Some(b'#') {
                return Err(self.unexpected("an entity instance '#id = ...;' or ENDSEC;"));
            }
            self.pos += 1;
            let id = self.digits_u64()?;
            self.expect(b'=', "'='")?;
            self.ws()?;
            if self.entities.len() >= self.limits.max_entities {
                return Err(self.limit_err(format!(
                    "more than {} entities (limit)",
                    self.limits.max_entities
                )));
            }
            let parts_start = self.parts.len();
            let complex = self.peek() == Some(b'(');
            if complex {
                self.pos += 1;
                loop {
                    self.ws()?;
                    if self.peek() == Some(b')') {
                        self.pos += 1;
                        break;
                    }
                    let name = self.keyword()?;
                    let args = self.params()?;
                    self.parts.push(Part { name, args });
                    if self.parts.len() - parts_start > u16::MAX as usize {
                        return Err(self.err("too many partial records in a complex entity"));
                    }
                }
                if self.parts.len() == parts_start {
                    return Err(self.err_at(start, "complex entity without records"));
                }
            } else {
                let name = self.keyword()?;
                let args = self.params()?;
                self.parts.push(Part { name, args });
            }
            self.expect(b';', "';' after the entity")?;
            self.entities.push(Entity {
                id,
                offset: start as u32,
                parts_start: parts_start as u32,
                parts_len: (self.parts.len() - parts_start) as u16,
                complex,
            });
        }
    }

    fn digits_u64(&mut self) -> PResult<u64> {
        let start = self.pos;
        let mut v: u64 = 0;
        while let Some(b) = self.peek() {
            if b.is_ascii_digit() {
                v = v
                    .checked_mul(10)
                    .and_then(|v| v.checked_add(u64::from(b - b'0')))
                    .ok_or_else(|| self.err_at(start, "entity id too large"))?;
                self.pos += 1;
            } else {
                break;
            }
        }
        if self.pos == start {
            return Err(self.unexpected("digits of an entity id"));
        }
        Ok(v)
    }

    fn string(&mut self) -> PResult<Span> {
        let open = self.pos;
        self.pos += 1;
        let start = self.pos;
        loop {
            match self.src[self.pos..].iter().position(|&b| b == b'\'') {
                None => {
                    return Err(self.err_at(open, "unterminated string"));
                }
                Some(p) => {
                    self.pos += p + 1;
                    if self.peek() == Some(b'\'') {
                        self.pos += 1;
                    } else {
                        return Ok(Span {
                            start: start as u32,
                            len: (self.pos - 1 - start) as u32,
                        });
                    }
                }
            }
        }
    }

    fn number(&mut self) -> PResult<Value> {
        let start = self.pos;
        if matches!(self.peek(), Some(b'+' | b'-')) {
            self.pos += 1;
        }
        let mut real = false;
        let digits_start = self.pos;
        while let Some(b) = self.peek() {
            match b {
                b'0'..=b'9' => self.pos += 1,
                b'.' => {
                    real = true;
                    self.pos += 1
                }
                b'E' | b'e' => {
                    real = true;
                    self.pos += 1;
                    if matches!(self.peek(), Some(b'+' | b'-')) {
                        self.pos += 1;
                    }
                }
                _ => break,
            }
        }
        if self.pos == digits_start {
            return Err(self.err_at(start, "a sign without a number"));
        }
        let text = std::str::from_utf8(&self.src[start..self.pos]).unwrap_or("");
        if !real {
            if let Ok(i) = text.parse::<i64>() {
                return Ok(Value::Int(i));
            }
        }
        match text.parse::<f64>() {
            Ok(f) => Ok(Value::Real(f)),
            Err(_) => Err(self.err_at(start, format!("malformed number '{text}'"))),
        }
    }

    /// Parses a parenthesised parameter list (cursor before '(') into the
    /// value arena, iteratively.
    fn params(&mut self) -> PResult<ListRange> {
        self.expect(b'(', "'('")?;
        // Each open list: (start in scratch, typed name if a typed parameter).
        let mut stack = std::mem::take(&mut self.stack);
        stack.clear();
        stack.push((self.scratch.len(), None));
        let r = self.params_inner(&mut stack);
        self.stack = stack;
        r
    }

    fn params_inner(&mut self, stack: &mut Vec<(usize, Option<Span>)>) -> PResult<ListRange> {
        let mut just_opened = true;
        loop {
            self.ws()?;
            let b = match self.peek() {
                Some(b) => b,
                None => return Err(self.err("unexpected end of file inside a parameter list")),
            };
            if just_opened && b == b')' {
                // Empty list: close it below.
            } else {
                let v = match b {
                    b'#' => {
                        self.pos += 1;
                        Value::Ref(self.digits_u64()?)
                    }
                    b'$' => {
                        self.pos += 1;
                        Value::Null
                    }
                    b'*' => {
                        self.pos += 1;
                        Value::Derived
                    }
                    b'\'' => Value::Str(self.string()?),
                    b'"' => {
                        let open = self.pos;
                        self.pos += 1;
                        let start = self.pos;
                        match self.src[self.pos..].iter().position(|&c| c == b'"') {
                            Some(p) => self.pos += p + 1,
                            None => return Err(self.err_at(open, "unterminated binary")),
                        }
                        Value::Binary(Span {
                            start: start as u32,
                            len: (self.pos - 1 - start) as u32,
                        })
                    }
                    b'.' => {
                        self.pos += 1;
                        let start = self.pos;
                        while let Some(c) = self.peek() {
                            if is_kw(c) {
                                self.pos += 1;
                            } else {
                                break;
                            }
                        }
                        if self.peek() != Some(b'.') || self.pos == start {
                            return Err(self.err_at(start - 1, "malformed enumeration"));
                        }
                        self.pos += 1;
                        Value::Enum(Span {
                            start: start as u32,
                            len: (self.pos - 1 - start) as u32,
                        })
                    }
                    b'0'..=b'9' | b'+' | b'-' => self.number()?,
                    b'(' => {
                        self.pos += 1;
                        self.open(stack, None)?;
                        just_opened = true;
                        continue;
                    }
                    c if is_kw_start(c) => {
                        let name = self.keyword()?;
                        self.expect(b'(', "'(' after a typed parameter name")?;
                        self.open(stack, Some(name))?;
                        just_opened = true;
                        continue;
                    }
                    _ => return Err(self.unexpected("a parameter")),
                };
                self.scratch.push(v);
                self.ws()?;
                match self.peek() {
                    Some(b',') => {
                        self.pos += 1;
                        just_opened = false;
                        continue;
                    }
                    Some(b')') => {}
                    _ => return Err(self.unexpected("',' or ')'")),
                }
            }
            // At a ')': close lists until a ',' follows.
            loop {
                self.pos += 1;
                if let Some(range) = self.close(stack)? {
                    return Ok(range);
                }
                self.ws()?;
                match self.peek() {
                    Some(b',') => {
                        self.pos += 1;
                        just_opened = false;
                        break;
                    }
                    Some(b')') => continue,
                    _ => return Err(self.unexpected("',' or ')'")),
                }
            }
        }
    }

    fn open(&mut self, stack: &mut Vec<(usize, Option<Span>)>, typed: Option<Span>) -> PResult<()> {
        if stack.len() >= self.limits.max_depth {
            return Err(self.limit_err(format!(
                "lists nested deeper than {} (limit)",
                self.limits.max_depth
            )));
        }
        stack.push((self.scratch.len(), typed));
        Ok(())
    }

    /// Closes the innermost open list; returns its range when it was the
    /// outermost one.
    fn close(&mut self, stack: &mut Vec<(usize, Option<Span>)>) -> PResult<Option<ListRange>> {
        let (start, typed) = match stack.pop() {
            Some(x) => x,
            None => return Err(self.err("internal: list stack empty")),
        };
        if self.values.len() + (self.scratch.len() - start) >= u32::MAX as usize {
            return Err(self.limit_err("too many parameters"));
        }
        let range = ListRange {
            start: self.values.len() as u32,
            len: (self.scratch.len() - start) as u32,
        };
        self.values.extend(self.scratch.drain(start..));
        if stack.is_empty() {
            return Ok(Some(range));
        }
        let v = match typed {
            Some(name) => Value::Typed { name, args: range },
            None => Value::List(range),
        };
        self.scratch.push(v);
        Ok(None)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const L: ParseLimits = ParseLimits {
        max_bytes: 1 << 20,
        max_entities: 1000,
        max_depth: 32,
    };

    fn wrap(data: &str) -> String {
        format!(
            "ISO-10303-21;\nHEADER;\nFILE_SCHEMA(('CONFIG_CONTROL_DESIGN'));\nENDSEC;\nDATA;\n{data}\nENDSEC;\nEND-ISO-10303-21;\n"
        )
    }

    #[test]
    fn parses_values() {
        let s = wrap(
            "/* c */ #1 = FOO('it''s',.T.,$,*,(),((1,2),(3.)),-1.E-3,0.5E+01,1.,LENGTH_MEASURE(2.),#7,\"0F\");\n#7=BAR();",
        );
        let ex = parse(s.as_bytes(), L).unwrap();
        assert_eq!(ex.schema(), "CONFIG_CONTROL_DESIGN");
        let e = ex.get(1).unwrap();
        let p = ex.parts_of(e)[0];
        assert_eq!(ex.name(p.name), "FOO");
        let a = ex.args(&p);
        assert_eq!(a.len(), 12);
        match a[0] {
            Value::Str(s) => assert_eq!(ex.string(s), "it's"),
            _ => panic!(),
        }
        assert!(matches!(a[1], Value::Enum(s) if ex.raw(s) == b"T"));
        assert_eq!(a[2], Value::Null);
        assert_eq!(a[3], Value::Derived);
        assert!(matches!(a[4], Value::List(l) if l.len == 0));
        match a[5] {
            Value::List(l) => {
                let inner = ex.list(l);
                assert_eq!(inner.len(), 2);
                assert!(
                    matches!(inner[0], Value::List(x) if ex.list(x) == [Value::Int(1), Value::Int(2)])
                );
                assert!(matches!(inner[1], Value::List(x) if ex.list(x) == [Value::Real(3.0)]));
            }
            _ => panic!(),
        }
        assert_eq!(a[6], Value::Real(-1e-3));
        assert_eq!(a[7], Value::Real(5.0));
        assert_eq!(a[8], Value::Real(1.0));
        assert!(
            matches!(a[9], Value::Typed{name, args} if ex.name(name) == "LENGTH_MEASURE" && ex.list(args) == [Value::Real(2.0)])
        );
        assert_eq!(a[10], Value::Ref(7));
        assert!(matches!(a[11], Value::Binary(_)));
        assert!(ex.get(7).is_some());
        assert!(ex.get(2).is_none());
    }

    #[test]
    fn complex_entity() {
        let s = wrap("#5=(GEOMETRIC_REPRESENTATION_CONTEXT(3) GLOBAL_UNIT_ASSIGNED_CONTEXT((#1,#2,#3)) REPRESENTATION_CONTEXT('',''));");
        let ex = parse(s.as_bytes(), L).unwrap();
        let e = ex.get(5).unwrap();
        assert!(e.complex);
        assert_eq!(ex.parts_of(e).len(), 3);
        let g = ex.part(e, "GLOBAL_UNIT_ASSIGNED_CONTEXT").unwrap();
        assert!(matches!(ex.args(g)[0], Value::List(l) if l.len == 3));
    }

    #[test]
    fn decodes_strings() {
        assert_eq!(decode_string(b"a''b"), "a'b");
        assert_eq!(decode_string(b"\\X2\\00E9\\X0\\t\\X\\E9"), "\u{e9}t\u{e9}");
        assert_eq!(decode_string(b"\\X4\\0001F600\\X0\\"), "\u{1F600}");
        assert_eq!(decode_string(b"a\\\\b"), "a\\b");
        assert_eq!(decode_string(b"\\S\\i"), "\u{e9}");
    }

    #[test]
    fn errors_have_places() {
        let s = wrap("#1=FOO(1,2;");
        let e = parse(s.as_bytes(), L).unwrap_err();
        assert_eq!(e.line, 6);
        assert!(e.reason.contains("expected"), "{e}");
        let s = wrap("#1=FOO(1);\n#1=BAR();");
        let e = parse(s.as_bytes(), L).unwrap_err();
        assert!(e.reason.contains("duplicate"), "{e}");
        let deep = format!("#1=FOO({}{});", "(".repeat(100), ")".repeat(100));
        let e = parse(wrap(&deep).as_bytes(), L).unwrap_err();
        assert!(e.limit);
    }
}
