//! Where a scene file said something and what is wrong with it: [`Loc`] (`file:line:column`)
//! and [`SceneError`], printed as one line (pbrt-v4's `FileLoc` and `ErrorExit`).
use std::fmt;
use std::path::PathBuf;
use std::sync::Arc;

/// Where in a scene file something was written: `file:line:column` (1-based).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Loc {
    pub file: Arc<PathBuf>,
    pub line: u32,
    pub col: u32,
}

impl fmt::Display for Loc {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}:{}:{}", self.file.display(), self.line, self.col)
    }
}

/// An error in a scene: where it is (when known) and what is wrong, as one line.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SceneError {
    pub loc: Option<Loc>,
    pub msg: String,
}

impl SceneError {
    pub fn at(loc: &Loc, msg: impl Into<String>) -> Self {
        SceneError {
            loc: Some(loc.clone()),
            msg: msg.into(),
        }
    }

    pub fn new(msg: impl Into<String>) -> Self {
        SceneError {
            loc: None,
            msg: msg.into(),
        }
    }
}

impl fmt::Display for SceneError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let msg = clip_for_message(&self.msg, MAX_MESSAGE);
        match &self.loc {
            Some(loc) => write!(
                f,
                "{}: {msg}",
                clip_for_message(&loc.to_string(), MAX_MESSAGE)
            ),
            None => write!(f, "{msg}"),
        }
    }
}

/// Longest message (in characters) an error prints.
pub const MAX_MESSAGE: usize = 600;
/// Longest token (in characters) an error quotes.
pub const MAX_TOKEN: usize = 40;

/// `s` made fit for one line of a terminal: control characters (newlines, NUL, ESC, ...)
/// escaped as `\n`, `\u{1b}`, and the text cut after `max` characters with an ellipsis.
pub fn clip_for_message(s: &str, max: usize) -> String {
    let mut out = String::new();
    for (n, c) in s.chars().enumerate() {
        if n >= max {
            out.push('…');
            break;
        }
        if c.is_control() {
            out.extend(c.escape_default());
        } else {
            out.push(c);
        }
    }
    out
}

/// Longest error line photon prints, in bytes: one readable line.
pub const MAX_LINE: usize = 200;

/// `s` as one line of at most `max` bytes: control characters escaped, and when longer, its
/// start (two thirds: where the error is) and its end (the last third: what is wrong) joined
/// by " … ".
pub fn one_line(s: &str, max: usize) -> String {
    // Control characters escaped, nothing clipped.
    let escaped = clip_for_message(s, usize::MAX);
    if escaped.len() <= max {
        return escaped;
    }
    let cut = |mut i: usize, down: bool| {
        while !escaped.is_char_boundary(i) {
            i = if down { i - 1 } else { i + 1 };
        }
        i
    };
    let head = cut(max * 2 / 3, true);
    let tail = cut(escaped.len() - (max - head - " … ".len()), false);
    format!("{} … {}", &escaped[..head], &escaped[tail..])
}

impl std::error::Error for SceneError {}
