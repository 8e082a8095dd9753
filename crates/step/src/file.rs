//! The exchange file: header, and an index of the data section's entity instances that are
//! parsed into values only when asked for.
//!
//! Reading is two passes of the same lexer. The first walks the whole file once, checks the
//! grammar of the header and of every instance's outline (balanced parentheses, `#id = …;`), and
//! records each instance's name, byte range and (for a simple instance) type — linear in the file
//! size, no per-instance allocation. The second parses one instance's attributes into
//! [`Value`]s when the model needs it, so a file's presentation and product data (often most of
//! it) is never parsed beyond the outline.
//!
//! Bounded work: nesting deeper than [`MAX_DEPTH`] is an error, numbers must be finite, and each
//! instance is parsed at most once per use.

use logos::Logos;

use crate::StepError;
use crate::lexer::Tok;

/// Deepest nesting of parentheses inside one instance.
pub const MAX_DEPTH: usize = 64;
/// Largest file accepted (bytes): far above real models; a guard against reading a disk image.
pub const MAX_FILE_BYTES: u64 = 4 << 30;

/// An attribute value.
#[derive(Clone, Debug, PartialEq)]
pub enum Value<'a> {
    /// An integer, e.g. `3`.
    Int(i64),
    /// A real, e.g. `2.5E-1`.
    Real(f64),
    /// The raw text between the quotes (escapes not decoded).
    Str(&'a str),
    /// The name between the dots of `.NAME.`.
    Enum(&'a str),
    /// A reference to an instance, `#id`.
    Ref(u64),
    /// A list `(…)` of values.
    List(Vec<Value<'a>>),
    /// A typed value `NAME(…)`, e.g. `LENGTH_MEASURE(25.4)`.
    Typed(&'a str, Vec<Value<'a>>),
    /// `$`: an optional value left out.
    Omitted,
    /// `*`: a value derived from a supertype.
    Derived,
    /// A binary value `"0F3A"` (its bits are not kept).
    Binary,
}

/// One part of an instance: the whole of a simple instance, or one of the partial entity values
/// of a complex one (`(A(…) B(…))`).
#[derive(Clone, Debug, PartialEq)]
pub struct Part<'a> {
    /// The entity type name, e.g. `CARTESIAN_POINT`.
    pub name: &'a str,
    /// The attribute values in file order.
    pub params: Vec<Value<'a>>,
}

/// A parsed instance.
#[derive(Clone, Debug, PartialEq)]
pub struct Instance<'a> {
    /// The instance's number (`#id`).
    pub id: u64,
    /// One part for a simple instance, several for a complex one.
    pub parts: Vec<Part<'a>>,
}

impl<'a> Instance<'a> {
    /// The type name of a simple instance, or the complex instance's part names joined by
    /// spaces, for messages.
    pub fn type_name(&self) -> String {
        match self.parts.as_slice() {
            [p] => p.name.to_string(),
            ps => format!(
                "({})",
                ps.iter().map(|p| p.name).collect::<Vec<_>>().join(" ")
            ),
        }
    }

    /// The part of the given type (the instance itself when simple and of that type).
    pub fn part(&self, name: &str) -> Option<&Part<'a>> {
        self.parts
            .iter()
            .find(|p| p.name.eq_ignore_ascii_case(name))
    }

    /// True for a simple instance of the type.
    pub fn is(&self, name: &str) -> bool {
        self.parts.len() == 1 && self.parts[0].name.eq_ignore_ascii_case(name)
    }
}

/// Where an instance sits in the text.
#[derive(Clone, Copy, Debug)]
struct Record {
    id: u64,
    /// Byte range of the value after `=` (without the `;`).
    start: usize,
    end: usize,
    /// Byte range of the type keyword of a simple instance; empty for a complex one.
    name: (usize, usize),
}

/// A STEP file: its text, header facts and the index of its instances.
#[derive(Debug)]
pub struct StepFile {
    text: String,
    /// The schemas `FILE_SCHEMA` names (e.g. `AUTOMOTIVE_DESIGN { 1 0 10303 214 1 1 1 1 }`).
    pub schemas: Vec<String>,
    records: Vec<Record>,
}

/// 1-based line of a byte offset.
fn line_of(text: &str, offset: usize) -> usize {
    text.as_bytes()[..offset.min(text.len())]
        .iter()
        .filter(|&&b| b == b'\n')
        .count()
        + 1
}

/// A token with its byte range.
#[derive(Clone, Copy, Debug)]
struct Token {
    tok: Tok,
    start: usize,
    end: usize,
}

/// The lexer with one token of look-ahead and the file offset of its slice.
struct Lexer<'a> {
    text: &'a str,
    base: usize,
    inner: logos::Lexer<'a, Tok>,
    peeked: Option<Option<Result<Token, usize>>>,
}

impl<'a> Lexer<'a> {
    fn new(text: &'a str, base: usize, end: usize) -> Self {
        Self {
            text,
            base,
            inner: Tok::lexer(&text[base..end]),
            peeked: None,
        }
    }

    fn lex(&mut self) -> Option<Result<Token, usize>> {
        let t = self.inner.next()?;
        let s = self.inner.span();
        Some(match t {
            Ok(tok) => Ok(Token {
                tok,
                start: self.base + s.start,
                end: self.base + s.end,
            }),
            Err(()) => Err(self.base + s.start),
        })
    }

    /// The next token; `Err(offset)` for an unlexable character, `None` at the end.
    fn next(&mut self) -> Option<Result<Token, usize>> {
        match self.peeked.take() {
            Some(t) => t,
            None => self.lex(),
        }
    }

    fn peek(&mut self) -> Option<Result<Token, usize>> {
        if self.peeked.is_none() {
            self.peeked = Some(self.lex());
        }
        self.peeked.unwrap_or(None)
    }

    fn slice(&self, t: Token) -> &'a str {
        &self.text[t.start..t.end]
    }
}

/// Context for syntax errors: which instance is being read.
struct SyntaxCtx<'a> {
    text: &'a str,
    entity: Option<u64>,
}

impl SyntaxCtx<'_> {
    fn at(&self, offset: usize, message: impl Into<String>) -> StepError {
        StepError::Syntax {
            line: line_of(self.text, offset),
            entity: self.entity,
            message: message.into(),
        }
    }

    fn bad_char(&self, offset: usize) -> StepError {
        let c = self.text[offset..].chars().next().unwrap_or('?');
        let what = match c {
            '\'' => "an unterminated string".to_string(),
            '/' => "an unterminated comment".to_string(),
            _ => format!("the character {c:?}"),
        };
        self.at(offset, format!("unexpected {what}"))
    }

    fn eof(&self, what: &str) -> StepError {
        self.at(
            self.text.len(),
            format!("the file ends {what} (is it truncated?)"),
        )
    }
}

fn expect(lx: &mut Lexer, cx: &SyntaxCtx, want: Tok, what: &str) -> Result<Token, StepError> {
    match lx.next() {
        Some(Ok(t)) if t.tok == want => Ok(t),
        Some(Ok(t)) => Err(cx.at(
            t.start,
            format!(
                "expected {} {what}, found {}",
                want.describe(),
                t.tok.describe()
            ),
        )),
        Some(Err(o)) => Err(cx.bad_char(o)),
        None => Err(cx.eof(what)),
    }
}

fn keyword(lx: &mut Lexer, cx: &SyntaxCtx, want: &str) -> Result<(), StepError> {
    let t = expect(lx, cx, Tok::Keyword, &format!("({want})"))?;
    if lx.slice(t).eq_ignore_ascii_case(want) {
        Ok(())
    } else {
        Err(cx.at(t.start, format!("expected {want}, found {}", lx.slice(t))))
    }
}

/// Skips a parenthesised group whose '(' was just read; returns the offset after its ')'.
fn skip_group(lx: &mut Lexer, cx: &SyntaxCtx, what: &str) -> Result<usize, StepError> {
    let mut depth = 1usize;
    loop {
        match lx.next() {
            Some(Ok(t)) => match t.tok {
                Tok::Open => {
                    depth += 1;
                    if depth > MAX_DEPTH {
                        return Err(cx.at(t.start, format!("nesting deeper than {MAX_DEPTH}")));
                    }
                }
                Tok::Close => {
                    depth -= 1;
                    if depth == 0 {
                        return Ok(t.end);
                    }
                }
                Tok::Semi => {
                    return Err(cx.at(t.start, format!("';' inside the parentheses of {what}")));
                }
                Tok::Begin | Tok::End => {
                    return Err(cx.at(t.start, format!("{} inside {what}", t.tok.describe())));
                }
                _ => {}
            },
            Some(Err(o)) => return Err(cx.bad_char(o)),
            None => return Err(cx.eof(&format!("inside {what}"))),
        }
    }
}

fn parse_id(text: &str, t: Token, cx: &SyntaxCtx) -> Result<u64, StepError> {
    text[t.start + 1..t.end]
        .parse::<u64>()
        .map_err(|_| cx.at(t.start, "instance number out of range"))
}

impl StepFile {
    /// Reads a file from disk.
    pub fn read(path: &std::path::Path) -> Result<StepFile, StepError> {
        let io = |e: std::io::Error| StepError::Io {
            path: path.to_path_buf(),
            message: e.to_string(),
        };
        let len = std::fs::metadata(path).map_err(io)?.len();
        if len > MAX_FILE_BYTES {
            return Err(StepError::TooLarge {
                bytes: len,
                limit: MAX_FILE_BYTES,
            });
        }
        let bytes = std::fs::read(path).map_err(io)?;
        let text = String::from_utf8(bytes).map_err(|e| {
            let offset = e.utf8_error().valid_up_to();
            let text = String::from_utf8_lossy(&e.into_bytes()[..offset]).into_owned();
            StepError::Syntax {
                line: line_of(&text, offset),
                entity: None,
                message: "the file is not text (invalid UTF-8); STEP files are ASCII".into(),
            }
        })?;
        StepFile::parse(text)
    }

    /// Indexes the text of an exchange file.
    pub fn parse(text: String) -> Result<StepFile, StepError> {
        let (schemas, records) = {
            let mut lx = Lexer::new(&text, 0, text.len());
            let cx = SyntaxCtx {
                text: &text,
                entity: None,
            };
            match lx.next() {
                Some(Ok(t)) if t.tok == Tok::Begin => {}
                _ => {
                    return Err(StepError::Header {
                        line: 1,
                        message:
                            "not an ISO 10303-21 (STEP) file: it must start with ISO-10303-21;"
                                .into(),
                    });
                }
            }
            expect(&mut lx, &cx, Tok::Semi, "after ISO-10303-21")?;
            let schemas = Self::header(&mut lx, &cx)?;
            let mut records: Vec<Record> = Vec::new();
            let mut sections = 0usize;
            loop {
                let t = match lx.next() {
                    Some(Ok(t)) => t,
                    Some(Err(o)) => return Err(cx.bad_char(o)),
                    None => return Err(cx.eof("before END-ISO-10303-21")),
                };
                match t.tok {
                    Tok::End => {
                        expect(&mut lx, &cx, Tok::Semi, "after END-ISO-10303-21")?;
                        break;
                    }
                    Tok::Keyword if lx.slice(t).eq_ignore_ascii_case("DATA") => {
                        if let Some(Ok(p)) = lx.peek()
                            && p.tok == Tok::Open
                        {
                            lx.next();
                            skip_group(&mut lx, &cx, "the DATA section's parameters")?;
                        }
                        expect(&mut lx, &cx, Tok::Semi, "after DATA")?;
                        Self::data(&mut lx, &text, &mut records)?;
                        sections += 1;
                    }
                    Tok::Keyword => {
                        return Err(cx.at(
                            t.start,
                            format!(
                                "the {} section is not supported (only HEADER and DATA)",
                                lx.slice(t)
                            ),
                        ));
                    }
                    other => {
                        return Err(cx.at(
                            t.start,
                            format!(
                                "expected DATA or END-ISO-10303-21, found {}",
                                other.describe()
                            ),
                        ));
                    }
                }
            }
            if sections == 0 {
                return Err(cx.at(text.len(), "the file has no DATA section"));
            }
            (schemas, records)
        };
        let mut records = records;
        records.sort_by_key(|r| r.id);
        if let Some(w) = records.windows(2).find(|w| w[0].id == w[1].id) {
            let (a, b) = (w[0].start.min(w[1].start), w[0].start.max(w[1].start));
            return Err(StepError::Duplicate {
                id: w[0].id,
                first_line: line_of(&text, a),
                second_line: line_of(&text, b),
            });
        }
        Ok(StepFile {
            text,
            schemas,
            records,
        })
    }

    /// The header section: `HEADER; …; ENDSEC;`; returns the schema names.
    fn header(lx: &mut Lexer, cx: &SyntaxCtx) -> Result<Vec<String>, StepError> {
        let head = |e: StepError| match e {
            StepError::Syntax { line, message, .. } => StepError::Header {
                line,
                message: format!("header: {message}"),
            },
            e => e,
        };
        keyword(lx, cx, "HEADER").map_err(head)?;
        expect(lx, cx, Tok::Semi, "after HEADER").map_err(head)?;
        let mut schemas = Vec::new();
        loop {
            let t = match lx.next() {
                Some(Ok(t)) => t,
                Some(Err(o)) => return Err(head(cx.bad_char(o))),
                None => return Err(head(cx.eof("inside the HEADER section"))),
            };
            if t.tok != Tok::Keyword {
                return Err(head(cx.at(
                    t.start,
                    format!(
                        "expected a header entity or ENDSEC, found {}",
                        t.tok.describe()
                    ),
                )));
            }
            let name = lx.slice(t);
            if name.eq_ignore_ascii_case("ENDSEC") {
                expect(lx, cx, Tok::Semi, "after ENDSEC").map_err(head)?;
                return Ok(schemas);
            }
            expect(lx, cx, Tok::Open, &format!("after {name}")).map_err(head)?;
            let is_schema = name.eq_ignore_ascii_case("FILE_SCHEMA");
            let mut depth = 1usize;
            while depth > 0 {
                match lx.next() {
                    Some(Ok(t)) => match t.tok {
                        Tok::Open => depth += 1,
                        Tok::Close => depth -= 1,
                        Tok::Str if is_schema => {
                            let s = lx.slice(t);
                            schemas.push(s[1..s.len() - 1].replace("''", "'"));
                        }
                        Tok::Semi => {
                            return Err(head(cx.at(t.start, format!("';' inside {name}"))));
                        }
                        _ => {}
                    },
                    Some(Err(o)) => return Err(head(cx.bad_char(o))),
                    None => return Err(head(cx.eof("inside the HEADER section"))),
                }
                if depth > MAX_DEPTH {
                    return Err(head(cx.at(0, format!("nesting deeper than {MAX_DEPTH}"))));
                }
            }
            expect(lx, cx, Tok::Semi, &format!("after {name}")).map_err(head)?;
        }
    }

    /// The outline of every instance of one DATA section, up to its ENDSEC.
    fn data(lx: &mut Lexer, text: &str, out: &mut Vec<Record>) -> Result<(), StepError> {
        let mut cx = SyntaxCtx { text, entity: None };
        loop {
            let t = match lx.next() {
                Some(Ok(t)) => t,
                Some(Err(o)) => return Err(cx.bad_char(o)),
                None => {
                    return Err(cx.eof(&match out.last() {
                        Some(r) => format!("inside the DATA section, after #{}", r.id),
                        None => "inside the DATA section".to_string(),
                    }));
                }
            };
            match t.tok {
                Tok::Keyword if lx.slice(t).eq_ignore_ascii_case("ENDSEC") => {
                    expect(lx, &cx, Tok::Semi, "after ENDSEC")?;
                    return Ok(());
                }
                Tok::Ref => {}
                other => {
                    return Err(cx.at(
                        t.start,
                        format!(
                            "expected an instance (#n = …;) or ENDSEC, found {}",
                            other.describe()
                        ),
                    ));
                }
            }
            cx.entity = None;
            let id = parse_id(text, t, &cx)?;
            cx.entity = Some(id);
            expect(lx, &cx, Tok::Eq, "after the instance name")?;
            let first = match lx.next() {
                Some(Ok(f)) => f,
                Some(Err(o)) => return Err(cx.bad_char(o)),
                None => return Err(cx.eof(&format!("inside #{id}"))),
            };
            let (name, end) = match first.tok {
                Tok::Keyword => {
                    expect(lx, &cx, Tok::Open, "after the entity name")?;
                    let end = skip_group(lx, &cx, &format!("#{id}"))?;
                    ((first.start, first.end), end)
                }
                Tok::Open => ((0, 0), skip_group(lx, &cx, &format!("#{id}"))?),
                other => {
                    return Err(cx.at(
                        first.start,
                        format!(
                            "expected an entity name or '(' after '=', found {}",
                            other.describe()
                        ),
                    ));
                }
            };
            expect(lx, &cx, Tok::Semi, &format!("at the end of #{id}"))?;
            out.push(Record {
                id,
                start: first.start,
                end,
                name,
            });
        }
    }

    fn record(&self, id: u64) -> Option<&Record> {
        self.records
            .binary_search_by_key(&id, |r| r.id)
            .ok()
            .map(|i| &self.records[i])
    }

    /// True when the file defines `#id`.
    pub fn contains(&self, id: u64) -> bool {
        self.record(id).is_some()
    }

    /// Number of instances.
    pub fn len(&self) -> usize {
        self.records.len()
    }

    /// True when the data section is empty.
    pub fn is_empty(&self) -> bool {
        self.records.is_empty()
    }

    /// The type name of a simple instance (`None` for a complex one or an unknown id), without
    /// parsing it.
    pub fn type_of(&self, id: u64) -> Option<&str> {
        let r = self.record(id)?;
        (r.name.1 > r.name.0).then(|| &self.text[r.name.0..r.name.1])
    }

    /// The ids of the simple instances of a type, in id order.
    pub fn ids_of_type<'s>(&'s self, name: &'s str) -> impl Iterator<Item = u64> + 's {
        self.records.iter().filter_map(move |r| {
            (r.name.1 > r.name.0 && self.text[r.name.0..r.name.1].eq_ignore_ascii_case(name))
                .then_some(r.id)
        })
    }

    /// The ids of the complex instances, in id order.
    pub fn complex_ids(&self) -> impl Iterator<Item = u64> + '_ {
        self.records
            .iter()
            .filter(|r| r.name.1 == r.name.0)
            .map(|r| r.id)
    }

    /// Parses instance `#id`; `from` is the instance that refers to it (for the error when the
    /// file does not define it).
    pub fn instance(&self, id: u64, from: u64) -> Result<Instance<'_>, StepError> {
        let r = self
            .record(id)
            .ok_or(StepError::Dangling { from, to: id })?;
        let cx = SyntaxCtx {
            text: &self.text,
            entity: Some(id),
        };
        let mut lx = Lexer::new(&self.text, r.start, r.end);
        let mut parts = Vec::new();
        let first = lx.next().ok_or_else(|| cx.eof("inside an instance"))?;
        let first = first.map_err(|o| cx.bad_char(o))?;
        if first.tok == Tok::Keyword {
            parts.push(Self::part(&mut lx, &cx, first)?);
        } else {
            // Complex: ( NAME(…) NAME(…) … )
            loop {
                match lx.next() {
                    Some(Ok(t)) if t.tok == Tok::Keyword => {
                        parts.push(Self::part(&mut lx, &cx, t)?)
                    }
                    Some(Ok(t)) if t.tok == Tok::Close => break,
                    Some(Ok(t)) => {
                        return Err(cx.at(
                            t.start,
                            format!("expected a partial entity name, found {}", t.tok.describe()),
                        ));
                    }
                    Some(Err(o)) => return Err(cx.bad_char(o)),
                    None => return Err(cx.eof("inside a complex instance")),
                }
            }
            if parts.is_empty() {
                return Err(cx.at(first.start, "an empty complex instance"));
            }
        }
        Ok(Instance { id, parts })
    }

    fn part<'a>(lx: &mut Lexer<'a>, cx: &SyntaxCtx, name: Token) -> Result<Part<'a>, StepError> {
        expect(lx, cx, Tok::Open, "after the entity name")?;
        let params = Self::values(lx, cx, 1)?;
        Ok(Part {
            name: lx.slice(name),
            params,
        })
    }

    /// Values up to the ')' closing the group just opened.
    fn values<'a>(
        lx: &mut Lexer<'a>,
        cx: &SyntaxCtx,
        depth: usize,
    ) -> Result<Vec<Value<'a>>, StepError> {
        let mut out = Vec::new();
        if let Some(Ok(t)) = lx.peek()
            && t.tok == Tok::Close
        {
            lx.next();
            return Ok(out);
        }
        loop {
            out.push(Self::value(lx, cx, depth)?);
            match lx.next() {
                Some(Ok(t)) if t.tok == Tok::Comma => {}
                Some(Ok(t)) if t.tok == Tok::Close => return Ok(out),
                Some(Ok(t)) => {
                    return Err(cx.at(
                        t.start,
                        format!("expected ',' or ')', found {}", t.tok.describe()),
                    ));
                }
                Some(Err(o)) => return Err(cx.bad_char(o)),
                None => return Err(cx.eof("inside a list")),
            }
        }
    }

    fn value<'a>(lx: &mut Lexer<'a>, cx: &SyntaxCtx, depth: usize) -> Result<Value<'a>, StepError> {
        let t = match lx.next() {
            Some(Ok(t)) => t,
            Some(Err(o)) => return Err(cx.bad_char(o)),
            None => return Err(cx.eof("inside a value")),
        };
        if depth >= MAX_DEPTH {
            return Err(cx.at(t.start, format!("nesting deeper than {MAX_DEPTH}")));
        }
        let s = lx.slice(t);
        Ok(match t.tok {
            Tok::Int => Value::Int(
                s.parse::<i64>()
                    .map_err(|_| cx.at(t.start, format!("integer {s} out of range")))?,
            ),
            Tok::Real => {
                let x = s
                    .parse::<f64>()
                    .map_err(|_| cx.at(t.start, format!("bad real number {s}")))?;
                if !x.is_finite() {
                    return Err(cx.at(t.start, format!("real number {s} is out of range")));
                }
                Value::Real(x)
            }
            Tok::Str => Value::Str(&s[1..s.len() - 1]),
            Tok::Enum => Value::Enum(&s[1..s.len() - 1]),
            Tok::Ref => Value::Ref(parse_id(cx.text, t, cx)?),
            Tok::Omitted => Value::Omitted,
            Tok::Derived => Value::Derived,
            Tok::Binary => Value::Binary,
            Tok::Open => Value::List(Self::values(lx, cx, depth + 1)?),
            Tok::Keyword => {
                expect(lx, cx, Tok::Open, &format!("after {s}"))?;
                Value::Typed(s, Self::values(lx, cx, depth + 1)?)
            }
            other => {
                return Err(cx.at(
                    t.start,
                    format!("unexpected {} in a value", other.describe()),
                ));
            }
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const SMALL: &str = "ISO-10303-21;\nHEADER;\nFILE_DESCRIPTION(('x'),'2;1');\nFILE_NAME('a','b',('c'),('d'),'e','f','g');\nFILE_SCHEMA(('AUTOMOTIVE_DESIGN { 1 0 10303 214 1 1 1 1 }'));\nENDSEC;\nDATA;\n#2 = CARTESIAN_POINT('',(1.,2.5,-3.E-01));\n#1 = ( LENGTH_UNIT() NAMED_UNIT(*) SI_UNIT(.MILLI.,.METRE.) );\n#3 = LENGTH_MEASURE_WITH_UNIT(LENGTH_MEASURE(25.4),#1);\nENDSEC;\nEND-ISO-10303-21;\n";

    #[test]
    fn indexes_and_parses_instances() {
        let f = StepFile::parse(SMALL.to_string()).unwrap();
        assert_eq!(f.len(), 3);
        assert_eq!(f.schemas, ["AUTOMOTIVE_DESIGN { 1 0 10303 214 1 1 1 1 }"]);
        assert_eq!(f.type_of(2), Some("CARTESIAN_POINT"));
        assert_eq!(f.type_of(1), None);
        let p = f.instance(2, 0).unwrap();
        assert!(p.is("CARTESIAN_POINT"));
        assert_eq!(
            p.parts[0].params[1],
            Value::List(vec![Value::Real(1.0), Value::Real(2.5), Value::Real(-0.3)])
        );
        let u = f.instance(1, 0).unwrap();
        assert_eq!(u.parts.len(), 3);
        assert_eq!(
            u.part("SI_UNIT").unwrap().params,
            [Value::Enum("MILLI"), Value::Enum("METRE")]
        );
        assert_eq!(u.part("NAMED_UNIT").unwrap().params, [Value::Derived]);
        let m = f.instance(3, 0).unwrap();
        assert_eq!(
            m.parts[0].params[0],
            Value::Typed("LENGTH_MEASURE", vec![Value::Real(25.4)])
        );
        assert_eq!(
            f.instance(7, 3).unwrap_err(),
            StepError::Dangling { from: 3, to: 7 }
        );
    }

    fn err(text: &str) -> String {
        StepFile::parse(text.to_string()).unwrap_err().to_string()
    }

    #[test]
    fn bad_files_name_the_line_and_instance() {
        let cut = &SMALL[..SMALL.find("#3").unwrap() + 20];
        let e = err(cut);
        assert!(e.contains("truncated") && e.contains("#3"), "{e}");
        let e = err(&SMALL.replace("ISO-10303-21;\nHEADER", "ISO-10303-22;\nHEADER"));
        assert!(e.contains("not an ISO 10303-21"), "{e}");
        let e = err(&SMALL.replace("(1.,2.5,", "(1.,2.5;"));
        assert!(e.starts_with("line 8 (#2)"), "{e}");
        let e = err(&SMALL.replace("#3 =", "#2 ="));
        assert!(e.contains("#2 is defined twice (lines 8 and 10)"), "{e}");
        let e = err(&SMALL.replace("'x'", "'x"));
        assert!(e.contains("header"), "{e}");
        let deep = format!(
            "{}#4 = X({}1{});\nENDSEC;\nEND-ISO-10303-21;\n",
            &SMALL[..SMALL.find("ENDSEC;\nEND").unwrap()],
            "(".repeat(80),
            ")".repeat(80)
        );
        assert!(err(&deep).contains("nesting deeper"));
        let f = StepFile::parse(SMALL.replace("-3.E-01", "1.E+999")).unwrap();
        let e = f.instance(2, 0).unwrap_err().to_string();
        assert!(e.contains("(#2)") && e.contains("out of range"), "{e}");
    }
}
