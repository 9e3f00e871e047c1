//! Test helpers shared by the workspace's test suites, so that every crate
//! checks its error messages the same way and leaves no scratch files
//! behind ([`Scratch`]). A development dependency only: no library depends
//! on it.

#![warn(missing_docs)]

use std::error::Error;

/// Each cause of `e` is shown once: by `source()`, not again in the message
/// of the error above it (the `aras` binary prints the whole chain, so a
/// repeated cause would be printed twice).
///
/// # Panics
/// When an error's message contains its source's message.
pub fn assert_source_not_repeated(e: &dyn Error) {
    let mut current = e;
    while let Some(c) = current.source() {
        assert!(
            !current.to_string().contains(&c.to_string()),
            "`{current}` repeats its source `{c}`"
        );
        current = c;
    }
}

/// The error's message and each of its causes, `": "`-separated, as the
/// `aras` binary prints them (one per line there), after checking that no
/// cause is repeated ([`assert_source_not_repeated`]).
pub fn error_chain(e: &dyn Error) -> String {
    assert_source_not_repeated(e);
    let mut text = e.to_string();
    let mut cause = e.source();
    while let Some(c) = cause {
        text = format!("{text}: {c}");
        cause = c.source();
    }
    text
}

/// The kind of the I/O error that is `e`'s direct source: a file error
/// keeps the operating system's error as its cause, not as text.
///
/// # Panics
/// When `e` has no source or its source is not a [`std::io::Error`].
pub fn io_source_kind(e: &dyn Error) -> std::io::ErrorKind {
    e.source()
        .and_then(|s| s.downcast_ref::<std::io::Error>())
        .unwrap_or_else(|| panic!("the source of `{e}` is not an I/O error"))
        .kind()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Debug)]
    struct Outer(&'static str, std::io::Error);
    impl std::fmt::Display for Outer {
        fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
            f.write_str(self.0)
        }
    }
    impl Error for Outer {
        fn source(&self) -> Option<&(dyn Error + 'static)> {
            Some(&self.1)
        }
    }

    #[test]
    fn chain_joins_causes_and_refuses_repeats() {
        let io = || std::io::Error::other("disk full");
        assert_eq!(
            error_chain(&Outer("writing x.csv", io())),
            "writing x.csv: disk full"
        );
        let repeated = std::panic::catch_unwind(|| {
            assert_source_not_repeated(&Outer("writing x.csv: disk full", io()))
        });
        assert!(repeated.is_err());
    }

    #[test]
    fn io_source_kind_reads_the_direct_source() {
        let missing = std::io::Error::from(std::io::ErrorKind::NotFound);
        assert_eq!(
            io_source_kind(&Outer("reading x.csv", missing)),
            std::io::ErrorKind::NotFound
        );
        let none = std::panic::catch_unwind(|| io_source_kind(&std::io::Error::other("x")));
        assert!(none.is_err());
    }
}

/// A fresh, empty scratch directory `aras-{tag}-{pid}` under the system's
/// temporary directory, removed with everything in it when dropped — unless
/// the test is panicking, so a failing test's files stay for inspection.
/// Dereferences to its [`Path`](std::path::Path).
#[derive(Debug)]
pub struct Scratch {
    path: std::path::PathBuf,
}

impl Scratch {
    /// Creates the directory, replacing a stale one of the same name (left
    /// by an earlier failing run of the same process id).
    ///
    /// # Panics
    /// When the directory cannot be created.
    pub fn new(tag: &str) -> Self {
        let path = std::env::temp_dir().join(format!("aras-{tag}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&path);
        std::fs::create_dir_all(&path)
            .unwrap_or_else(|e| panic!("creating the scratch directory {}: {e}", path.display()));
        Self { path }
    }

    /// The directory.
    pub fn path(&self) -> &std::path::Path {
        &self.path
    }
}

impl std::ops::Deref for Scratch {
    type Target = std::path::Path;
    fn deref(&self) -> &std::path::Path {
        &self.path
    }
}

impl AsRef<std::path::Path> for Scratch {
    fn as_ref(&self) -> &std::path::Path {
        &self.path
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        if !std::thread::panicking() {
            let _ = std::fs::remove_dir_all(&self.path);
        }
    }
}
