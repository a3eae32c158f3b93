//! Splits pbrt-v4 scene text into tokens, each with its 1-based line and column.
//!
//! The syntax it reads:
//!
//! ```text
//! # a comment runs to the end of the line
//! Shape "trianglemesh" "point3 P" [ 0 0 0  1 0 0  0 1 0 ]   # quoted strings, [ ] lists
//! Translate 1 -2.5e-1 3                                     # bare numbers and words
//! ```
//!
//! Tokens borrow their text from the source (no allocation per token); strings keep their
//! escape sequences until [`unescape`] is asked for their value. A newline or end of file inside
//! a quoted string is an error at the opening quote, as in pbrt-v4.

use crate::scene::{Loc, SceneError};
use std::borrow::Cow;
use std::path::PathBuf;
use std::sync::Arc;

/// What kind of token this is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TokKind {
    /// A quoted string; `text` is what stands between the quotes (escapes not yet resolved).
    Str,
    /// An unquoted word that does not start like a number: a directive, `true`, `false`.
    Word,
    /// An unquoted word that starts like a number (digit, sign or dot).
    Num,
    /// `[`
    Open,
    /// `]`
    Close,
}

/// One token: its kind, its text (borrowed from the file) and where it starts.
#[derive(Clone, Copy, Debug)]
pub struct Token<'a> {
    pub kind: TokKind,
    pub text: &'a str,
    pub line: u32,
    pub col: u32,
}

impl Token<'_> {
    /// A short description for error messages: `string "abc"`, `number 1.5`, `"["`.
    pub fn describe(&self) -> String {
        let text = self.clipped();
        match self.kind {
            TokKind::Str => format!("string \"{text}\""),
            TokKind::Word => format!("word {text}"),
            TokKind::Num => format!("number {text}"),
            TokKind::Open => "\"[\"".to_string(),
            TokKind::Close => "\"]\"".to_string(),
        }
    }
}

impl Token<'_> {
    /// The token's text for a message: control characters escaped, cut to
    /// [`crate::scene::MAX_TOKEN`] characters with an ellipsis.
    pub fn clipped(&self) -> String {
        crate::scene::clip_for_message(self.text, crate::scene::MAX_TOKEN)
    }
}

/// A `# comment` as written (text from the `#` to the end of its line) and where it starts;
/// kept only by a tokenizer made with [`Tokenizer::keeping_comments`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Comment<'a> {
    pub text: &'a str,
    pub line: u32,
    pub col: u32,
}

/// A tokenizer over one file's text, with one token of look-ahead.
pub struct Tokenizer<'a> {
    src: &'a str,
    pos: usize,
    line: u32,
    line_start: usize,
    file: Arc<PathBuf>,
    peeked: Option<Token<'a>>,
    /// The comments skipped so far and not yet taken, when they are kept.
    comments: Option<Vec<Comment<'a>>>,
}

impl<'a> Tokenizer<'a> {
    /// Tokenizes `src`, the text of `file` (which is only used to build locations).
    pub fn new(src: &'a str, file: Arc<PathBuf>) -> Self {
        Tokenizer {
            src,
            pos: 0,
            line: 1,
            line_start: 0,
            file,
            peeked: None,
            comments: None,
        }
    }

    /// Keeps the comments it skips, for [`Tokenizer::take_comments`] (`photon upgrade` writes
    /// them back out; the loader drops them).
    pub fn keeping_comments(mut self) -> Self {
        self.comments = Some(Vec::new());
        self
    }

    /// The comments skipped since the last call, in file order (always empty unless made with
    /// [`Tokenizer::keeping_comments`]). A peeked token's comments are among them.
    pub fn take_comments(&mut self) -> Vec<Comment<'a>> {
        self.comments
            .as_mut()
            .map(std::mem::take)
            .unwrap_or_default()
    }

    /// The file being read.
    pub fn file(&self) -> &Arc<PathBuf> {
        &self.file
    }

    /// The location of `tok` in this file.
    pub fn loc(&self, tok: &Token) -> Loc {
        self.loc_at(tok.line, tok.col)
    }

    /// The location `line:col` in this file.
    pub fn loc_at(&self, line: u32, col: u32) -> Loc {
        Loc {
            file: self.file.clone(),
            line,
            col,
        }
    }

    /// The location just past the last token (for "unexpected end of file").
    pub fn end_loc(&self) -> Loc {
        let col = (self.src.len() - self.line_start.min(self.src.len())) as u32 + 1;
        self.loc_at(self.line, col)
    }

    /// An error at `tok`.
    pub fn err(&self, tok: &Token, msg: impl Into<String>) -> SceneError {
        SceneError::at(&self.loc(tok), msg)
    }

    /// The next token without consuming it.
    pub fn peek(&mut self) -> Result<Option<Token<'a>>, SceneError> {
        if self.peeked.is_none() {
            self.peeked = self.scan()?;
        }
        Ok(self.peeked)
    }

    /// Consumes and returns the next token (`None` at end of file).
    #[allow(clippy::should_implement_trait)]
    pub fn next(&mut self) -> Result<Option<Token<'a>>, SceneError> {
        match self.peeked.take() {
            Some(t) => Ok(Some(t)),
            None => self.scan(),
        }
    }

    /// Consumes the next token, which must exist (`what` names what was expected).
    pub fn next_required(&mut self, what: &str) -> Result<Token<'a>, SceneError> {
        match self.next()? {
            Some(t) => Ok(t),
            None => Err(SceneError::at(
                &self.end_loc(),
                format!("unexpected end of file: expected {what}"),
            )),
        }
    }

    /// Skips whitespace and comments, counting lines.
    fn skip_blank(&mut self) {
        let bytes = self.src.as_bytes();
        while self.pos < bytes.len() {
            match bytes[self.pos] {
                b'\n' => {
                    self.pos += 1;
                    self.line += 1;
                    self.line_start = self.pos;
                }
                b' ' | b'\t' | b'\r' | b'\x0c' | b'\x0b' => self.pos += 1,
                b'#' => {
                    let start = self.pos;
                    while self.pos < bytes.len() && bytes[self.pos] != b'\n' {
                        self.pos += 1;
                    }
                    if let Some(kept) = &mut self.comments {
                        kept.push(Comment {
                            text: self.src[start..self.pos].trim_end(),
                            line: self.line,
                            col: (start - self.line_start) as u32 + 1,
                        });
                    }
                }
                _ => break,
            }
        }
    }

    /// Reads the next token from the text.
    fn scan(&mut self) -> Result<Option<Token<'a>>, SceneError> {
        self.skip_blank();
        let bytes = self.src.as_bytes();
        if self.pos >= bytes.len() {
            return Ok(None);
        }
        let start = self.pos;
        let line = self.line;
        let col = (start - self.line_start) as u32 + 1;
        let mk = |kind, text| Token {
            kind,
            text,
            line,
            col,
        };
        match bytes[start] {
            b'[' => {
                self.pos += 1;
                Ok(Some(mk(TokKind::Open, "[")))
            }
            b']' => {
                self.pos += 1;
                Ok(Some(mk(TokKind::Close, "]")))
            }
            b'"' => {
                let end = self.scan_string_end(start, line, col)?;
                self.pos = end + 1;
                Ok(Some(mk(TokKind::Str, &self.src[start + 1..end])))
            }
            first => {
                let mut end = start;
                while end < bytes.len()
                    && !matches!(
                        bytes[end],
                        b' ' | b'\t'
                            | b'\r'
                            | b'\n'
                            | b'\x0c'
                            | b'\x0b'
                            | b'"'
                            | b'['
                            | b']'
                            | b'#'
                    )
                {
                    end += 1;
                }
                self.pos = end;
                let kind = if first.is_ascii_digit() || matches!(first, b'-' | b'+' | b'.') {
                    TokKind::Num
                } else {
                    TokKind::Word
                };
                Ok(Some(mk(kind, &self.src[start..end])))
            }
        }
    }

    /// Finds the closing quote of the string opening at `start`; a newline or the end of the
    /// file first is an error at the opening quote.
    fn scan_string_end(&self, start: usize, line: u32, col: u32) -> Result<usize, SceneError> {
        let bytes = self.src.as_bytes();
        let mut i = start + 1;
        while i < bytes.len() {
            match bytes[i] {
                b'"' => return Ok(i),
                b'\\' if bytes.get(i + 1) != Some(&b'\n') => i += 2,
                b'\\' | b'\n' => {
                    return Err(SceneError::at(
                        &self.loc_at(line, col),
                        "unterminated string (newline before the closing quote)",
                    ))
                }
                _ => i += 1,
            }
        }
        Err(SceneError::at(
            &self.loc_at(line, col),
            "unterminated string (end of file before the closing quote)",
        ))
    }
}

/// The value of a string token: its text with pbrt's escapes (`\n \t \b \f \r \\ \' \"`)
/// resolved. Borrowed when there is nothing to resolve.
pub fn unescape(text: &str) -> Cow<'_, str> {
    if !text.contains('\\') {
        return Cow::Borrowed(text);
    }
    let mut out = String::with_capacity(text.len());
    let mut chars = text.chars();
    while let Some(c) = chars.next() {
        if c != '\\' {
            out.push(c);
            continue;
        }
        match chars.next() {
            Some('n') => out.push('\n'),
            Some('t') => out.push('\t'),
            Some('b') => out.push('\x08'),
            Some('f') => out.push('\x0c'),
            Some('r') => out.push('\r'),
            Some(other) => out.push(other),
            None => out.push('\\'),
        }
    }
    Cow::Owned(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn toks(src: &str) -> Vec<(TokKind, String, u32, u32)> {
        let mut t = Tokenizer::new(src, Arc::new(PathBuf::from("t.pbrt")));
        let mut out = Vec::new();
        while let Some(tok) = t.next().unwrap() {
            out.push((tok.kind, tok.text.to_string(), tok.line, tok.col));
        }
        out
    }

    #[test]
    fn kinds_lines_and_columns() {
        let got = toks("Shape \"a b\" [1 -2.5]# c\n  x");
        let want = vec![
            (TokKind::Word, "Shape".to_string(), 1, 1),
            (TokKind::Str, "a b".to_string(), 1, 7),
            (TokKind::Open, "[".to_string(), 1, 13),
            (TokKind::Num, "1".to_string(), 1, 14),
            (TokKind::Num, "-2.5".to_string(), 1, 16),
            (TokKind::Close, "]".to_string(), 1, 20),
            (TokKind::Word, "x".to_string(), 2, 3),
        ];
        assert_eq!(got, want);
    }

    #[test]
    fn unterminated_string_is_an_error_at_the_quote() {
        let mut t = Tokenizer::new("a\n  \"abc\n\"", Arc::new(PathBuf::from("t.pbrt")));
        t.next().unwrap();
        let e = t.next().unwrap_err();
        assert_eq!(e.loc.as_ref().map(|l| (l.line, l.col)), Some((2, 3)));
        assert!(e.msg.contains("unterminated string"));
    }

    #[test]
    fn comments_are_kept_only_when_asked() {
        let src = "# a\nShape # b \r\n\"x\"";
        let mut t = Tokenizer::new(src, Arc::new(PathBuf::from("t.pbrt"))).keeping_comments();
        assert_eq!(t.next().unwrap().unwrap().text, "Shape");
        let got: Vec<_> = t
            .take_comments()
            .iter()
            .map(|c| (c.text, c.line, c.col))
            .collect();
        assert_eq!(got, vec![("# a", 1, 1)]);
        assert_eq!(t.next().unwrap().unwrap().text, "x");
        let got: Vec<_> = t
            .take_comments()
            .iter()
            .map(|c| (c.text, c.line, c.col))
            .collect();
        assert_eq!(got, vec![("# b", 2, 7)]);
        let mut plain = Tokenizer::new(src, Arc::new(PathBuf::from("t.pbrt")));
        while plain.next().unwrap().is_some() {}
        assert!(plain.take_comments().is_empty());
    }

    #[test]
    fn escapes_resolve() {
        assert_eq!(unescape(r#"a\"b\\c\n"#), "a\"b\\c\n");
        assert!(matches!(unescape("plain"), Cow::Borrowed("plain")));
    }
}
