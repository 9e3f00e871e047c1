//! The record of what a run wrote: which files, and their exact contents
//! (size and hash), so that `--force` replaces a file only while it is
//! still byte for byte what the tool wrote.

use std::collections::{BTreeMap, BTreeSet};
use std::fs;
use std::io::Read;
use std::path::{Component, Path, PathBuf};

use anyhow::{Context, Result, bail};
use serde::{Deserialize, Serialize};

/// Name of the manifest in every run directory the tool writes.
pub const MANIFEST: &str = ".aras-manifest.json";

/// Format tag of [`Manifest`]: names with their [`Digest`]s.
pub const MANIFEST_FORMAT: &str = "aras-manifest/2";

/// The earlier format, names only: still read, and then a listed file
/// counts as the tool's whatever its content.
const MANIFEST_FORMAT_NAMES_ONLY: &str = "aras-manifest/1";

/// Size and 64-bit FNV-1a hash of a file's bytes. It tells whether a file
/// is still exactly what the tool wrote (an edit, a copy of another file
/// over it); it is not a defence against someone forging a collision.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Digest {
    /// Length in bytes.
    pub bytes: u64,
    /// FNV-1a (64-bit) of the bytes, as 16 lowercase hex digits.
    #[serde(with = "hex64")]
    pub fnv1a64: u64,
}

impl Digest {
    /// The digest of the file at `path` (read once, in 1 MiB pieces).
    pub fn of_file(path: &Path) -> std::io::Result<Self> {
        let mut f = fs::File::open(path)?;
        let mut buf = vec![0u8; 1 << 20];
        let mut d = Self::of_bytes(&[]);
        loop {
            let n = f.read(&mut buf)?;
            if n == 0 {
                return Ok(d);
            }
            d.extend(&buf[..n]);
        }
    }

    /// The digest of `bytes`.
    pub fn of_bytes(bytes: &[u8]) -> Self {
        let mut d = Self {
            bytes: 0,
            fnv1a64: 0xcbf2_9ce4_8422_2325,
        };
        d.extend(bytes);
        d
    }

    fn extend(&mut self, bytes: &[u8]) {
        let mut h = self.fnv1a64;
        for &b in bytes {
            h ^= u64::from(b);
            h = h.wrapping_mul(0x0100_0000_01b3);
        }
        self.fnv1a64 = h;
        self.bytes += bytes.len() as u64;
    }
}

mod hex64 {
    use serde::{Deserialize, Deserializer, Serializer, de::Error};

    pub fn serialize<S: Serializer>(v: &u64, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(&format!("{v:016x}"))
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<u64, D::Error> {
        let s = String::deserialize(d)?;
        if s.len() != 16 {
            return Err(D::Error::custom("expected 16 hex digits"));
        }
        u64::from_str_radix(&s, 16).map_err(D::Error::custom)
    }
}

/// The list of files a run wrote, with their digests: stored as
/// [`MANIFEST`] in a run directory, and as the record beside a single-file
/// output (`.NAME.aras-manifest.json`, see [`super::NewFile`]).
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Manifest {
    /// [`MANIFEST_FORMAT`] (or the names-only `aras-manifest/1`).
    pub format: String,
    /// The tool and its version that wrote the files, e.g. `aras 0.1.0`.
    pub tool: String,
    /// For a single-file output, what kind of file it is
    /// ([`super::FileKind::id`]); absent for a run directory.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub kind: Option<String>,
    /// Paths of the files written, relative to the directory, with `/`
    /// separators (the manifest itself is not listed).
    pub files: Vec<String>,
    /// The digest of every listed file, as written.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub digests: BTreeMap<String, Digest>,
}

impl Manifest {
    /// The manifest of the files under `dir` (recursively), as they are now.
    pub fn of_dir(dir: &Path) -> Result<Self> {
        let mut files = Vec::new();
        let mut dirs = Vec::new();
        walk(dir, dir, &mut files, &mut dirs)?;
        files.retain(|f| f != MANIFEST);
        files.sort();
        Self::of_files(dir, files, None)
    }

    /// The manifest of `files` (relative to `dir`), with their digests now.
    pub fn of_files(dir: &Path, files: Vec<String>, kind: Option<&str>) -> Result<Self> {
        let mut digests = BTreeMap::new();
        for f in &files {
            let p = dir.join(f);
            let d = Digest::of_file(&p).with_context(|| format!("cannot read {}", p.display()))?;
            digests.insert(f.clone(), d);
        }
        Ok(Self {
            format: MANIFEST_FORMAT.into(),
            tool: format!("aras {}", env!("CARGO_PKG_VERSION")),
            kind: kind.map(str::to_owned),
            files,
            digests,
        })
    }

    /// Reads `dir`'s [`MANIFEST`]: `None` when there is none.
    pub fn read(dir: &Path) -> Result<Option<Self>> {
        Self::read_file(&dir.join(MANIFEST))
    }

    /// Reads the manifest at `path`: `None` when there is none. A listed
    /// path that is absolute or leaves the directory (`..`) is an error:
    /// such a manifest was not written by this tool and is never followed.
    pub fn read_file(path: &Path) -> Result<Option<Self>> {
        let text = match fs::read_to_string(path) {
            Ok(t) => t,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
            Err(e) => return Err(e).with_context(|| format!("cannot read {}", path.display())),
        };
        let m: Self = serde_json::from_str(&text).with_context(|| {
            format!(
                "{} is not a manifest written by aras; move the files elsewhere or choose \
                 another --out",
                path.display()
            )
        })?;
        if m.format != MANIFEST_FORMAT && m.format != MANIFEST_FORMAT_NAMES_ONLY {
            bail!(
                "{}: unknown manifest format `{}` (expected `{MANIFEST_FORMAT}`); \
                 choose another --out",
                path.display(),
                m.format
            );
        }
        for f in m.files.iter().chain(m.digests.keys()) {
            if !is_plain_relative(f) {
                bail!(
                    "{}: the listed path `{f}` is not inside the directory (absolute or with `..`); \
                     the manifest is not followed and nothing is replaced; choose another --out",
                    path.display()
                );
            }
        }
        if m.format == MANIFEST_FORMAT
            && let Some(f) = m.files.iter().find(|f| !m.digests.contains_key(*f))
        {
            bail!(
                "{}: `{f}` is listed without its digest, so the manifest was not written by \
                 aras; nothing is replaced; choose another --out",
                path.display()
            );
        }
        Ok(Some(m))
    }

    /// Checks that the listed file `rel` in `dir` is still what was written:
    /// an error naming it when its size or content differs. A manifest of
    /// the names-only format vouches for the name alone.
    pub fn check_unchanged(&self, dir: &Path, rel: &str) -> Result<()> {
        let Some(want) = self.digests.get(rel) else {
            if self.format == MANIFEST_FORMAT_NAMES_ONLY && self.files.iter().any(|f| f == rel) {
                return Ok(());
            }
            bail!(
                "{} is not listed in the record of what aras wrote; --force replaces only \
                 what aras wrote. Move it elsewhere or choose another --out",
                dir.join(rel).display()
            );
        };
        let p = dir.join(rel);
        let now = Digest::of_file(&p).with_context(|| format!("cannot read {}", p.display()))?;
        if now != *want {
            bail!(
                "{} has changed since aras wrote it ({} bytes now, {} written; the content \
                 differs), so it is treated as yours; --force replaces only what aras wrote. \
                 Move it elsewhere or choose another --out",
                p.display(),
                now.bytes,
                want.bytes
            );
        }
        Ok(())
    }

    /// Writes the manifest to `path` atomically (pretty JSON, newline).
    pub(super) fn write_to(&self, path: &Path) -> Result<()> {
        let mut text = serde_json::to_string_pretty(self).context("cannot serialise JSON")?;
        text.push('\n');
        super::write_atomic(path, text.as_bytes())
    }
}

/// A relative path made only of normal components (no root, no `.`/`..`).
fn is_plain_relative(p: &str) -> bool {
    !p.is_empty()
        && !p.contains('\\')
        && Path::new(p)
            .components()
            .all(|c| matches!(c, Component::Normal(_)))
}

/// Files (as `/`-separated relative paths) and directories under `dir`.
/// Symbolic links count as files and are not followed.
pub(super) fn walk(
    root: &Path,
    dir: &Path,
    files: &mut Vec<String>,
    dirs: &mut Vec<PathBuf>,
) -> Result<()> {
    for e in fs::read_dir(dir).with_context(|| format!("cannot read {}", dir.display()))? {
        let e = e.with_context(|| format!("cannot read {}", dir.display()))?;
        let p = e.path();
        let ty = e
            .file_type()
            .with_context(|| format!("cannot read {}", p.display()))?;
        if ty.is_dir() {
            dirs.push(p.clone());
            walk(root, &p, files, dirs)?;
        } else {
            let rel = p.strip_prefix(root).unwrap_or(&p);
            let parts: Vec<String> = rel
                .components()
                .map(|c| c.as_os_str().to_string_lossy().into_owned())
                .collect();
            files.push(parts.join("/"));
        }
    }
    Ok(())
}

/// Checks that every entry of the existing run directory `target` is listed
/// in its manifest and unchanged, so replacing it loses nothing the tool
/// did not write.
pub(super) fn check_replaceable(target: &Path) -> Result<Manifest> {
    let Some(manifest) = Manifest::read(target)? else {
        bail!(
            "output directory {} exists, is not empty and has no {MANIFEST}, so it was not \
             written by aras; --force replaces only directories aras wrote. Move its files \
             elsewhere or choose another --out",
            target.display()
        );
    };
    let mut files = Vec::new();
    let mut dirs = Vec::new();
    walk(target, target, &mut files, &mut dirs)?;
    let listed: BTreeSet<&str> = manifest.files.iter().map(String::as_str).collect();
    for f in &files {
        if f == MANIFEST {
            continue;
        }
        if !listed.contains(f.as_str()) {
            bail!(
                "output directory {} holds {}, which aras did not write (it is not in {MANIFEST}); \
                 --force replaces only what aras wrote. Move that file elsewhere or choose another --out",
                target.display(),
                target.join(f).display()
            );
        }
        manifest.check_unchanged(target, f)?;
    }
    // A directory is ours when it holds (at some depth) a listed file.
    for d in &dirs {
        let rel = d.strip_prefix(target).unwrap_or(d);
        let prefix: Vec<String> = rel
            .components()
            .map(|c| c.as_os_str().to_string_lossy().into_owned())
            .collect();
        let prefix = prefix.join("/") + "/";
        if !files.iter().any(|f| f.starts_with(&prefix)) {
            bail!(
                "output directory {} holds the empty directory {}, which aras did not write; \
                 remove it or choose another --out",
                target.display(),
                d.display()
            );
        }
    }
    Ok(manifest)
}

/// Removes the files of `manifest` from `dir`, then the directories left
/// empty; anything else stays (and is reported in the error).
pub(super) fn remove_listed(dir: &Path, manifest: &Manifest) -> Result<()> {
    for f in &manifest.files {
        let p = dir.join(f);
        match fs::remove_file(&p) {
            Ok(()) => {}
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
            Err(e) => return Err(e).with_context(|| format!("cannot remove {}", p.display())),
        }
    }
    let _ = fs::remove_file(dir.join(MANIFEST));
    let mut files = Vec::new();
    let mut dirs = Vec::new();
    walk(dir, dir, &mut files, &mut dirs)?;
    // Deepest first; `remove_dir` only removes empty directories.
    dirs.sort_by_key(|d| std::cmp::Reverse(d.components().count()));
    for d in dirs {
        let _ = fs::remove_dir(d);
    }
    fs::remove_dir(dir).with_context(|| {
        format!(
            "{} still holds files aras did not write; they were kept",
            dir.display()
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The published FNV-1a 64 test vectors, and pieces equal to the whole.
    #[test]
    fn digest_is_fnv1a_64() {
        assert_eq!(Digest::of_bytes(b"").fnv1a64, 0xcbf29ce484222325);
        assert_eq!(Digest::of_bytes(b"a").fnv1a64, 0xaf63dc4c8601ec8c);
        assert_eq!(Digest::of_bytes(b"foobar").fnv1a64, 0x85944171f73967e8);
        let mut d = Digest::of_bytes(b"foo");
        d.extend(b"bar");
        assert_eq!(d, Digest::of_bytes(b"foobar"));
        assert_eq!(d.bytes, 6);
    }

    #[test]
    fn digests_round_trip_as_hex() {
        let d = Digest::of_bytes(b"t,tau1,tau2\n");
        let s = serde_json::to_string(&d).unwrap();
        assert!(s.contains(&format!("\"{:016x}\"", d.fnv1a64)), "{s}");
        assert_eq!(serde_json::from_str::<Digest>(&s).unwrap(), d);
        assert!(serde_json::from_str::<Digest>(r#"{"bytes":1,"fnv1a64":"zz"}"#).is_err());
    }
}
