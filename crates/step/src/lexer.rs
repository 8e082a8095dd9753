//! The tokens of an ISO 10303-21 exchange file, lexed by `logos` (a DFA built at compile time).
//!
//! Whitespace and `/* … */` comments are skipped. Keywords are upper case in the standard; lower
//! case is accepted. Strings keep their raw text (escapes such as `''` or `\X2\…\X0\` are not
//! decoded: names do not matter for geometry).

use logos::Logos;

/// One token; its text is the lexer's slice.
#[derive(Logos, Clone, Copy, Debug, PartialEq, Eq)]
#[logos(skip r"[ \t\r\n\f]+")]
#[logos(skip r"/\*([^*]|\*+[^*/])*\*+/")]
pub enum Tok {
    /// `ISO-10303-21` (the file's first token).
    #[token("ISO-10303-21")]
    Begin,
    /// `END-ISO-10303-21` (its last).
    #[token("END-ISO-10303-21")]
    End,
    /// `#123`: an entity instance name (a reference, or the name being defined).
    #[regex(r"#[0-9]+")]
    Ref,
    /// `@123`: a value instance name (rare; reported as unsupported).
    #[regex(r"@[0-9]+")]
    ValueRef,
    #[token("=")]
    /// `=`.
    Eq,
    #[token("(")]
    /// `(`.
    Open,
    #[token(")")]
    /// `)`.
    Close,
    #[token(",")]
    /// `,`.
    Comma,
    #[token(";")]
    /// `;`: the end of an instance or header entry.
    Semi,
    /// `$`: an omitted optional value.
    #[token("$")]
    Omitted,
    /// `*`: a value derived from a supertype.
    #[token("*")]
    Derived,
    /// An entity or type name (`CARTESIAN_POINT`) or a section name (`DATA`).
    #[regex(r"[A-Za-z_][A-Za-z0-9_]*")]
    Keyword,
    /// A user-defined keyword (`!NAME`).
    #[regex(r"![A-Za-z_][A-Za-z0-9_]*")]
    UserKeyword,
    /// `.T.`, `.F.`, `.UNSPECIFIED.`
    #[regex(r"\.[A-Za-z_][A-Za-z0-9_]*\.")]
    Enum,
    #[regex(r"[+-]?[0-9]+")]
    /// An integer, e.g. `-12`.
    Int,
    #[regex(r"[+-]?[0-9]+\.[0-9]*([eE][+-]?[0-9]+)?")]
    #[regex(r"[+-]?\.[0-9]+([eE][+-]?[0-9]+)?")]
    /// A real: digits with a decimal point, an optional exponent.
    Real,
    #[regex(r"'([^']|'')*'")]
    /// A string `'…'` (a quote inside doubled).
    Str,
    /// `"0F3A"`: a binary value.
    #[regex(r#""[0-9A-Fa-f]*""#)]
    Binary,
}

impl Tok {
    /// How the token is named in error messages.
    pub fn describe(self) -> &'static str {
        match self {
            Tok::Begin => "ISO-10303-21",
            Tok::End => "END-ISO-10303-21",
            Tok::Ref => "an entity reference",
            Tok::ValueRef => "a value reference",
            Tok::Eq => "'='",
            Tok::Open => "'('",
            Tok::Close => "')'",
            Tok::Comma => "','",
            Tok::Semi => "';'",
            Tok::Omitted => "'$'",
            Tok::Derived => "'*'",
            Tok::Keyword => "a keyword",
            Tok::UserKeyword => "a user keyword",
            Tok::Enum => "an enumeration",
            Tok::Int => "an integer",
            Tok::Real => "a real number",
            Tok::Str => "a string",
            Tok::Binary => "a binary value",
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn toks(s: &str) -> Vec<(Tok, &str)> {
        let mut lx = Tok::lexer(s);
        let mut out = Vec::new();
        while let Some(t) = lx.next() {
            out.push((t.expect("lexes"), lx.slice()));
        }
        out
    }

    #[test]
    fn an_entity_instance() {
        let t = toks("#12 = CARTESIAN_POINT('it''s',(0.,-8.8E-16,20.)) /* c */;");
        let kinds: Vec<Tok> = t.iter().map(|x| x.0).collect();
        assert_eq!(
            kinds,
            [
                Tok::Ref,
                Tok::Eq,
                Tok::Keyword,
                Tok::Open,
                Tok::Str,
                Tok::Comma,
                Tok::Open,
                Tok::Real,
                Tok::Comma,
                Tok::Real,
                Tok::Comma,
                Tok::Real,
                Tok::Close,
                Tok::Close,
                Tok::Semi
            ]
        );
        assert_eq!(t[4].1, "'it''s'");
        assert_eq!(t[9].1, "-8.8E-16");
    }

    #[test]
    fn header_markers_enums_and_specials() {
        let t = toks("ISO-10303-21; .UNSPECIFIED. $ * 7 -3 1.E-07 END-ISO-10303-21;");
        let kinds: Vec<Tok> = t.iter().map(|x| x.0).collect();
        assert_eq!(
            kinds,
            [
                Tok::Begin,
                Tok::Semi,
                Tok::Enum,
                Tok::Omitted,
                Tok::Derived,
                Tok::Int,
                Tok::Int,
                Tok::Real,
                Tok::End,
                Tok::Semi
            ]
        );
    }

    #[test]
    fn unterminated_string_and_comment_are_errors() {
        assert!(Tok::lexer("'abc").any(|t| t.is_err()));
        assert!(Tok::lexer("/* abc").any(|t| t.is_err()));
        assert!(Tok::lexer("#1 = X(%);").any(|t| t.is_err()));
    }
}
