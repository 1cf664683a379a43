//! The tokens of a Rust source file, enough to see its module structure: identifiers, `::`,
//! single punctuation characters and string literals (kept for `#[path = "..."]`). Comments,
//! doc comments, character literals and lifetimes are dropped; numbers become [`Tok::Other`].

/// One token and the line it starts on (1-based).
#[derive(Clone, Debug, PartialEq)]
pub struct Token {
    /// What the token is.
    pub tok: Tok,
    /// The line it starts on, counted from 1.
    pub line: u32,
}

/// The kinds of token the module walk distinguishes.
#[derive(Clone, Debug, PartialEq)]
pub enum Tok {
    /// An identifier or keyword (`r#type` becomes `type`).
    Ident(String),
    /// The path separator `::`.
    PathSep,
    /// Any other punctuation character.
    Punct(char),
    /// A string literal's contents (escapes left as written).
    Str(String),
    /// A number or other literal the walk does not need.
    Other,
}

impl Tok {
    /// The identifier, if this is one.
    pub fn ident(&self) -> Option<&str> {
        match self {
            Tok::Ident(s) => Some(s),
            _ => None,
        }
    }

    /// Whether this is the punctuation character `c`.
    pub fn is(&self, c: char) -> bool {
        *self == Tok::Punct(c)
    }

    /// Whether this is the identifier (or keyword) `word`.
    pub fn is_word(&self, word: &str) -> bool {
        self.ident() == Some(word)
    }
}

/// Splits `src` into tokens. Never fails: an unterminated comment or literal ends at the end of
/// the file.
pub fn lex(src: &str) -> Vec<Token> {
    let chars: Vec<char> = src.chars().collect();
    let mut out = Vec::new();
    let mut i = 0;
    let mut line = 1u32;
    let n = chars.len();
    let at = |i: usize| chars.get(i).copied().unwrap_or('\0');
    while i < n {
        let c = chars[i];
        let start_line = line;
        if c == '\n' {
            line += 1;
            i += 1;
        } else if c.is_whitespace() {
            i += 1;
        } else if c == '/' && at(i + 1) == '/' {
            while i < n && chars[i] != '\n' {
                i += 1;
            }
        } else if c == '/' && at(i + 1) == '*' {
            let mut depth = 0;
            while i < n {
                if chars[i] == '/' && at(i + 1) == '*' {
                    depth += 1;
                    i += 2;
                } else if chars[i] == '*' && at(i + 1) == '/' {
                    depth -= 1;
                    i += 2;
                    if depth == 0 {
                        break;
                    }
                } else {
                    if chars[i] == '\n' {
                        line += 1;
                    }
                    i += 1;
                }
            }
        } else if let Some((len, hashes)) = raw_string_start(&chars, i) {
            // r"..", r#".."#, br"..", cr".."
            i += len;
            let begin = i;
            loop {
                if i >= n {
                    break;
                }
                if chars[i] == '"' && (0..hashes).all(|k| at(i + 1 + k) == '#') {
                    break;
                }
                if chars[i] == '\n' {
                    line += 1;
                }
                i += 1;
            }
            let text: String = chars[begin..i.min(n)].iter().collect();
            i += 1 + hashes;
            out.push(Token {
                tok: Tok::Str(text),
                line: start_line,
            });
        } else if c == '"' || ((c == 'b' || c == 'c') && at(i + 1) == '"') {
            i += if c == '"' { 1 } else { 2 };
            let begin = i;
            while i < n && chars[i] != '"' {
                if chars[i] == '\\' {
                    i += 1;
                }
                if at(i) == '\n' {
                    line += 1;
                }
                i += 1;
            }
            let text: String = chars[begin..i.min(n)].iter().collect();
            i += 1;
            out.push(Token {
                tok: Tok::Str(text),
                line: start_line,
            });
        } else if c == '\'' || (c == 'b' && at(i + 1) == '\'') {
            // A character literal ('x', '\n', b'x') or a lifetime / label ('a): both dropped.
            let q = if c == '\'' { i } else { i + 1 };
            if at(q + 1) == '\\' {
                i = q + 2;
                while i < n && chars[i] != '\'' {
                    i += 1;
                }
                i += 1;
            } else if at(q + 2) == '\'' {
                i = q + 3;
            } else {
                i = q + 1;
                while i < n && (chars[i].is_alphanumeric() || chars[i] == '_') {
                    i += 1;
                }
            }
        } else if c.is_alphabetic() || c == '_' {
            if c == 'r' && at(i + 1) == '#' && (at(i + 2).is_alphabetic() || at(i + 2) == '_') {
                i += 2;
            }
            let begin = i;
            while i < n && (chars[i].is_alphanumeric() || chars[i] == '_') {
                i += 1;
            }
            let word: String = chars[begin..i].iter().collect();
            out.push(Token {
                tok: Tok::Ident(word),
                line: start_line,
            });
        } else if c.is_ascii_digit() {
            while i < n && (chars[i].is_alphanumeric() || chars[i] == '_') {
                i += 1;
            }
            // A fraction, but not a range (`0..n`) or a method on an integer (`1.max(x)`).
            if at(i) == '.' && at(i + 1).is_ascii_digit() {
                i += 1;
                while i < n && (chars[i].is_alphanumeric() || chars[i] == '_') {
                    i += 1;
                }
            }
            out.push(Token {
                tok: Tok::Other,
                line: start_line,
            });
        } else if c == ':' && at(i + 1) == ':' {
            i += 2;
            out.push(Token {
                tok: Tok::PathSep,
                line: start_line,
            });
        } else {
            i += 1;
            out.push(Token {
                tok: Tok::Punct(c),
                line: start_line,
            });
        }
    }
    out
}

/// If a raw string literal starts at `i`: the length of its opening (prefix, hashes, quote) and
/// its number of hashes.
fn raw_string_start(chars: &[char], i: usize) -> Option<(usize, usize)> {
    let mut j = i;
    if matches!(chars.get(j), Some('b') | Some('c')) {
        j += 1;
    }
    if chars.get(j) != Some(&'r') {
        return None;
    }
    // Not part of a longer identifier such as `bar"`: the caller only asks at a token start.
    j += 1;
    let mut hashes = 0;
    while chars.get(j) == Some(&'#') {
        hashes += 1;
        j += 1;
    }
    (chars.get(j) == Some(&'"')).then_some((j + 1 - i, hashes))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn idents(src: &str) -> Vec<String> {
        lex(src)
            .into_iter()
            .filter_map(|t| t.tok.ident().map(str::to_string))
            .collect()
    }

    #[test]
    fn comments_strings_chars_and_lifetimes_are_not_identifiers() {
        let src = "/* a /* nested */ crate::x */ // crate::y\n\
                   fn f<'a>(s: &'a str) -> char { let _ = r#\"crate::z \"q\"\"#; let c = '\\''; 'x' }";
        assert_eq!(
            idents(src),
            ["fn", "f", "s", "str", "char", "let", "_", "let", "c"]
        );
    }

    #[test]
    fn path_separators_lines_and_strings() {
        let toks = lex("use crate::a;\n#[path = \"b.rs\"]\nmod b;");
        assert_eq!(toks[1].tok, Tok::Ident("crate".into()));
        assert_eq!(toks[2].tok, Tok::PathSep);
        assert_eq!(toks[2].line, 1);
        let path = toks.iter().find(|t| matches!(t.tok, Tok::Str(_))).unwrap();
        assert_eq!((path.tok.clone(), path.line), (Tok::Str("b.rs".into()), 2));
        assert_eq!(toks.last().unwrap().line, 3);
    }

    #[test]
    fn numbers_ranges_and_raw_identifiers() {
        assert_eq!(idents("0..n; 1.5e3; 2.max(r#type)"), ["n", "max", "type"]);
    }
}
