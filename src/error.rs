//! The one error type of sgbem.
//!
//! Every failure a user can cause is an [`Error`] whose message names the file and the
//! offending key, group, node or element, and says how to fix it. The kind decides the
//! exit status of the command line (README "Command line"): input errors 2, numerical
//! failures 3, anything else (I/O) 1.

use std::fmt;
use std::path::Path;

/// What went wrong, with a message written for the user.
#[derive(Debug, Clone, PartialEq)]
pub enum Error {
    /// Invalid scene, mesh, or combination of both (exit 2).
    Input { file: String, message: String },
    /// Singular or ill-posed system, solver not converged (exit 3).
    Numerical { message: String },
    /// Reading or writing files failed (exit 1).
    Io { file: String, message: String },
}

impl Error {
    pub fn input(file: impl AsRef<Path>, message: impl Into<String>) -> Self {
        Error::Input {
            file: file.as_ref().display().to_string(),
            message: bounded(message.into()),
        }
    }

    pub fn numerical(message: impl Into<String>) -> Self {
        Error::Numerical {
            message: bounded(message.into()),
        }
    }

    /// An I/O error; one of a full file system (ENOSPC, os error 28) says what to do.
    pub fn io(file: impl AsRef<Path>, err: impl fmt::Display) -> Self {
        let mut message = err.to_string();
        if message.contains("(os error 28)") {
            message += "; the file system is full: free space there, write elsewhere (--out \
                        DIR), or ask for smaller outputs in [output] (history = \"steps\" or \
                        \"final\", every = N, vtk_fields, vtk = \"compressed\"; `sgbem check` \
                        prints their estimated size)";
        }
        Error::Io {
            file: file.as_ref().display().to_string(),
            message: bounded(message),
        }
    }

    /// Exit status for the command line, as README "Command line" fixes it.
    pub fn exit_code(&self) -> i32 {
        match self {
            Error::Input { .. } => 2,
            Error::Numerical { .. } => 3,
            Error::Io { .. } => 1,
        }
    }

    /// The message without the file prefix.
    pub fn message(&self) -> &str {
        match self {
            Error::Input { message, .. }
            | Error::Numerical { message }
            | Error::Io { message, .. } => message,
        }
    }
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::Input { file, message } => write!(f, "{file}: {message}"),
            Error::Numerical { message } => write!(f, "numerical failure: {message}"),
            Error::Io { file, message } => write!(f, "{file}: {message}"),
        }
    }
}

impl std::error::Error for Error {}

pub type Result<T> = std::result::Result<T, Error>;

/// The longest line of a message, in characters: a longer one (a hostile input quoted
/// whole: a TOML line of 200 000 brackets, a `--set` value of megabytes) keeps its start and
/// its end, which says how to fix it.
const MAX_LINE: usize = 1200;

/// `message` with every line of more than [`MAX_LINE`] characters shortened in the middle.
pub(crate) fn bounded(message: String) -> String {
    if message.lines().all(|l| l.chars().count() <= MAX_LINE) {
        return message;
    }
    message
        .split('\n')
        .map(|line| {
            let n = line.chars().count();
            if n <= MAX_LINE {
                return line.to_string();
            }
            let (keep_head, keep_tail) = (MAX_LINE * 2 / 3, MAX_LINE / 4);
            let head: String = line.chars().take(keep_head).collect();
            let tail: String = line.chars().skip(n - keep_tail).collect();
            let left = n - keep_head - keep_tail;
            format!("{head} … ({left} characters left out) … {tail}")
        })
        .collect::<Vec<_>>()
        .join("\n")
}

/// The candidate closest to `name` by edit distance, if close enough to be a likely typo.
pub fn nearest<'a>(name: &str, candidates: impl Iterator<Item = &'a str>) -> Option<&'a str> {
    let limit = (name.chars().count() / 3).max(2);
    candidates
        .map(|c| (edit_distance(&name.to_lowercase(), &c.to_lowercase()), c))
        .filter(|(d, _)| *d <= limit)
        .min_by_key(|(d, _)| *d)
        .map(|(_, c)| c)
}

/// " (did you mean `x`?)" when a candidate is close to `name`, else "".
pub(crate) fn did_you_mean<'a>(name: &str, candidates: impl Iterator<Item = &'a str>) -> String {
    match nearest(name, candidates) {
        Some(c) => format!(" (did you mean `{c}`?)"),
        None => String::new(),
    }
}

/// Levenshtein distance between two strings, by characters.
fn edit_distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut row: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut diag = row[0];
        row[0] = i + 1;
        for (j, cb) in b.iter().enumerate() {
            let next = (row[j + 1] + 1)
                .min(row[j] + 1)
                .min(diag + usize::from(ca != *cb));
            diag = row[j + 1];
            row[j + 1] = next;
        }
    }
    row[b.len()]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nearest_finds_typos_only() {
        let keys = ["young", "poisson", "body_force"];
        assert_eq!(nearest("yuong", keys.iter().copied()), Some("young"));
        assert_eq!(nearest("poison", keys.iter().copied()), Some("poisson"));
        assert_eq!(nearest("density", keys.iter().copied()), None);
        assert_eq!(edit_distance("kitten", "sitting"), 3);
    }

    #[test]
    fn long_lines_of_a_message_keep_their_start_and_end() {
        let m = format!("start {} end", "x".repeat(100_000));
        let e = Error::input("scene.toml", format!("short line\n{m}"));
        let text = e.message();
        assert!(text.starts_with("short line\nstart xxx") && text.ends_with("xxx end"));
        assert!(text.contains("characters left out"), "{text}");
        assert!(
            text.lines().all(|l| l.chars().count() <= MAX_LINE),
            "{}",
            text.len()
        );
        assert_eq!(Error::io("a", "as it was").message(), "as it was");
    }

    #[test]
    fn exit_codes_follow_the_spec() {
        assert_eq!(Error::input("a", "b").exit_code(), 2);
        assert_eq!(Error::numerical("b").exit_code(), 3);
        assert_eq!(Error::io("a", "b").exit_code(), 1);
    }
}
