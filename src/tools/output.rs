//! Output files of a subcommand: planned and checked before any work is done, written to
//! temporary files, and renamed into place together at the end.
//!
//! ```text
//! photon render scene.pbrt -o out.exr --png out.png    # two regular files: temps, then renames
//! photon render scene.pbrt -o /dev/null --no-png       # a device or FIFO is written directly
//! photon render scene.pbrt -o link.exr                 # a symlink: its target is replaced
//! ```
//!
//! [`Outputs::plan`] (or [`Outputs::plan_files`] for any set of files) resolves symlinks to
//! the file they name, refuses directories, sockets and block devices, refuses two outputs that
//! are the same file (and `-o` with a `.png` extension, which the preview would overwrite), and
//! proves each regular destination's directory writable by creating and removing a probe file.
//! [`Outputs::commit`] (or [`Outputs::write`] for a render's EXR and PNG) writes every file to
//! a hidden temporary beside its destination (`.NAME.<pid>.photon-tmp.EXT`) and renames them
//! all only when every one is complete; a character device or a FIFO gets the finished bytes
//! copied in, never a rename, so `/dev/null` stays a device. It installs the SIGINT/SIGTERM
//! flag ([`crate::interrupt`]) for the writing phase and polls it after each file: on a signal
//! the temporaries are removed, nothing is renamed, and [`OutputError::Interrupted`] tells the
//! caller which exit code to use (130/143).
use crate::imageio::{self, ExrPixel, RgbImage};
use crate::interrupt::{self, Signal};
use std::fs;
use std::io;
use std::path::{Path, PathBuf};

/// Why outputs could not be planned or written.
#[derive(Debug, PartialEq, Eq)]
pub enum OutputError {
    /// A one-line message naming the flag or file.
    Bad(String),
    /// A signal arrived while writing: temporaries removed, nothing replaced.
    Interrupted(Signal),
}

impl std::fmt::Display for OutputError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            OutputError::Bad(m) => f.write_str(m),
            OutputError::Interrupted(s) => write!(
                f,
                "interrupted by {} while writing the outputs: temporary files removed, nothing replaced",
                s.name()
            ),
        }
    }
}

impl From<OutputError> for super::ToolError {
    fn from(e: OutputError) -> Self {
        super::ToolError(e.to_string())
    }
}

/// How a destination is written.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Kind {
    /// A regular file (or none yet): temporary file beside it, then rename.
    Regular,
    /// A character device or FIFO: the finished bytes are copied in.
    Special,
}

/// One planned output.
#[derive(Clone, Debug)]
pub struct OutputFile {
    /// The flag that named it (`-o`, `--png`), for messages.
    pub flag: String,
    /// The path as given.
    pub shown: PathBuf,
    /// The file actually written: `shown` with symlinks followed.
    pub dest: PathBuf,
    kind: Kind,
}

/// Checked output files, written together by [`Outputs::commit`].
#[derive(Clone, Debug)]
pub struct Outputs {
    pub files: Vec<OutputFile>,
}

/// A writer of one output into the path it is given.
pub type Writer<'a> = Box<dyn FnOnce(&Path) -> Result<(), String> + 'a>;

/// The PNG preview's default path beside the EXR `exr` (its `.png` sibling), or `None` when
/// `exr` is a device or a FIFO (`-o /dev/null` must not create `/dev/null.png`).
pub fn default_png(exr: &Path) -> Option<PathBuf> {
    use std::os::unix::fs::FileTypeExt;
    let special = fs::metadata(exr).is_ok_and(|m| {
        let t = m.file_type();
        t.is_char_device() || t.is_fifo() || t.is_block_device() || t.is_socket()
    });
    (!special).then(|| exr.with_extension("png"))
}

/// Symlinks followed before giving up (the kernel's own limit).
const MAX_LINKS: usize = 40;

/// `path` with every symlink in its last component followed (a dangling link names the file
/// to create).
fn follow_links(path: &Path) -> Result<PathBuf, String> {
    let mut p = path.to_path_buf();
    for _ in 0..MAX_LINKS {
        match fs::symlink_metadata(&p) {
            Ok(m) if m.file_type().is_symlink() => {
                let target = fs::read_link(&p).map_err(|e| format!("{e}"))?;
                p = match p.parent() {
                    Some(dir) => dir.join(target),
                    None => target,
                };
            }
            _ => return Ok(p),
        }
    }
    Err("too many levels of symbolic links".to_string())
}

/// The directory a file at `p` goes into (`.` for a bare name).
fn dir_of(p: &Path) -> PathBuf {
    match p.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

/// `p` with its directory made absolute and canonical, for comparing destinations.
fn identity(p: &Path) -> PathBuf {
    let dir = fs::canonicalize(dir_of(p)).unwrap_or_else(|_| dir_of(p));
    match p.file_name() {
        Some(n) => dir.join(n),
        None => dir,
    }
}

/// A hidden temporary name beside `dest`: `.NAME.<pid>.photon-tmp.EXT`.
fn temp_beside(dest: &Path) -> PathBuf {
    let name = dest.file_name().unwrap_or_default().to_string_lossy();
    let mut tmp = format!(".{name}.{}.photon-tmp", std::process::id());
    if let Some(ext) = dest.extension() {
        tmp.push('.');
        tmp.push_str(&ext.to_string_lossy());
    }
    dest.with_file_name(tmp)
}

/// A temporary file for a special destination number `i`, in the system's temporary directory.
fn temp_elsewhere(dest: &Path, i: usize) -> PathBuf {
    let ext = dest.extension().unwrap_or_default().to_string_lossy();
    std::env::temp_dir().join(format!("photon-{}-{i}.tmp.{ext}", std::process::id()))
}

/// Checks one output and decides how it will be written.
fn plan_one(flag: &str, shown: &Path) -> Result<OutputFile, String> {
    let bad = |what: String| format!("{flag} {}: {what}", shown.display());
    if shown.file_name().is_none() {
        return Err(bad("not a file name".into()));
    }
    let dest = follow_links(shown).map_err(bad)?;
    let kind = match fs::metadata(&dest) {
        Ok(m) => {
            use std::os::unix::fs::FileTypeExt;
            let t = m.file_type();
            if t.is_file() {
                Kind::Regular
            } else if t.is_char_device() || t.is_fifo() {
                Kind::Special
            } else if t.is_dir() {
                return Err(bad("is a directory".into()));
            } else {
                return Err(bad(
                    "is not a regular file, a character device or a FIFO".into()
                ));
            }
        }
        Err(e) if e.kind() == io::ErrorKind::NotFound => Kind::Regular,
        Err(e) => return Err(bad(e.to_string())),
    };
    if kind == Kind::Regular {
        probe_dir(&dest).map_err(|e| {
            bad(format!(
                "cannot write in directory {}: {e}",
                dir_of(&dest).display()
            ))
        })?;
    }
    Ok(OutputFile {
        flag: flag.to_string(),
        shown: shown.to_path_buf(),
        dest,
        kind,
    })
}

/// Proves a file can be created beside `dest` (creates and removes the temporary).
fn probe_dir(dest: &Path) -> io::Result<()> {
    let tmp = temp_beside(dest);
    fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(&tmp)?;
    fs::remove_file(&tmp)
}

impl Outputs {
    /// Plans `files` (`(flag, path)` pairs): each checked as the module describes, and no two
    /// naming the same file.
    pub fn plan_files(files: &[(&str, &Path)]) -> Result<Outputs, String> {
        let mut planned: Vec<OutputFile> = Vec::new();
        for (flag, path) in files {
            let f = plan_one(flag, path)?;
            if let Some(o) = planned
                .iter()
                .find(|o| o.kind == Kind::Regular && identity(&o.dest) == identity(&f.dest))
            {
                return Err(format!(
                    "{} {} and {} {} are the same file: one would overwrite the other",
                    o.flag,
                    o.shown.display(),
                    f.flag,
                    f.shown.display()
                ));
            }
            planned.push(f);
        }
        Ok(Outputs { files: planned })
    }

    /// A render's outputs: the EXR (`-o`) and the optional PNG preview (`--png`).
    pub fn plan(exr: &Path, png: Option<&Path>) -> Result<Outputs, String> {
        let ext = exr
            .extension()
            .map(|e| e.to_string_lossy().to_ascii_lowercase());
        if ext.as_deref() == Some("png") {
            return Err(format!(
                "-o {}: -o names the EXR; the PNG preview goes to --png",
                exr.display()
            ));
        }
        let mut files = vec![("-o", exr)];
        files.extend(png.map(|p| ("--png", p)));
        Outputs::plan_files(&files)
    }

    /// Writes each file with its writer (one per planned file, in order) to a temporary, then
    /// puts them all in place. On an error or a signal the temporaries are removed and no
    /// destination is touched.
    pub fn commit(&self, writers: Vec<Writer>) -> Result<(), OutputError> {
        assert_eq!(writers.len(), self.files.len(), "one writer per output");
        interrupt::install();
        let temps: Vec<PathBuf> = self
            .files
            .iter()
            .enumerate()
            .map(|(i, f)| match f.kind {
                Kind::Regular => temp_beside(&f.dest),
                Kind::Special => temp_elsewhere(&f.dest, i),
            })
            .collect();
        let result = self.write_temps(writers, &temps).and_then(|()| {
            check_signal()?;
            self.place(&temps)
        });
        for t in &temps {
            let _ = fs::remove_file(t);
        }
        result
    }

    /// Runs the writers into the temporaries, polling for a signal after each.
    fn write_temps(&self, writers: Vec<Writer>, temps: &[PathBuf]) -> Result<(), OutputError> {
        for ((f, w), tmp) in self.files.iter().zip(writers).zip(temps) {
            check_signal()?;
            w(tmp)
                .map_err(|m| OutputError::Bad(format!("{} {}: {m}", f.flag, f.shown.display())))?;
        }
        check_signal()
    }

    /// Renames (or copies, for special files) every temporary into place.
    fn place(&self, temps: &[PathBuf]) -> Result<(), OutputError> {
        for (f, tmp) in self.files.iter().zip(temps) {
            let done = match f.kind {
                Kind::Regular => fs::rename(tmp, &f.dest),
                Kind::Special => copy_into(tmp, &f.dest),
            };
            done.map_err(|e| OutputError::Bad(format!("{} {}: {e}", f.flag, f.shown.display())))?;
        }
        Ok(())
    }

    /// A render's EXR (with its component layers) and PNG preview, as planned by [`Self::plan`].
    pub fn write(
        &self,
        image: &RgbImage,
        layers: &[(&str, &RgbImage)],
        pixel: ExrPixel,
        exposure: f32,
    ) -> Result<(), OutputError> {
        let mut writers: Vec<Writer> = vec![Box::new(move |tmp: &Path| {
            imageio::write_exr(tmp, image, layers, pixel).map_err(|e| kind_only(&e))
        })];
        if self.files.len() > 1 {
            writers.push(Box::new(move |tmp: &Path| {
                imageio::write_png(tmp, image, exposure).map_err(|e| kind_only(&e))
            }));
        }
        self.commit(writers)
    }
}

/// An image error without its (temporary) path: the caller names the destination.
fn kind_only(e: &imageio::ImageError) -> String {
    let full = e.to_string();
    let prefix = format!("{}: ", e.path.display());
    full.strip_prefix(&prefix).unwrap_or(&full).to_string()
}

/// `Err(Interrupted)` once a signal has arrived.
fn check_signal() -> Result<(), OutputError> {
    match interrupt::requested() {
        Some(s) => Err(OutputError::Interrupted(s)),
        None => Ok(()),
    }
}

/// Copies the finished file `tmp` into the existing device or FIFO `dest` (never created,
/// truncated or replaced).
fn copy_into(tmp: &Path, dest: &Path) -> io::Result<()> {
    let mut src = fs::File::open(tmp)?;
    let mut out = fs::OpenOptions::new().write(true).open(dest)?;
    io::copy(&mut src, &mut out).map(|_| ())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dir(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("photon-output-{name}-{}", std::process::id()));
        let _ = fs::remove_dir_all(&d);
        fs::create_dir_all(&d).unwrap();
        d
    }

    fn names(d: &Path) -> Vec<String> {
        let mut v: Vec<String> = fs::read_dir(d)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }

    fn text(s: &'static str) -> Writer<'static> {
        Box::new(move |p: &Path| fs::write(p, s).map_err(|e| e.to_string()))
    }

    #[test]
    fn collisions_and_png_extension_are_refused() {
        let d = dir("collide");
        let a = d.join("a.exr");
        let e = Outputs::plan(&a, Some(&a)).unwrap_err();
        assert!(e.contains("same file"), "{e}");
        let e = Outputs::plan(&d.join("x.PNG"), None).unwrap_err();
        assert!(e.contains("--png"), "{e}");
        // The same file through a symlink and through `..`.
        std::os::unix::fs::symlink(&a, d.join("link.png")).unwrap();
        let e = Outputs::plan(&a, Some(&d.join("link.png"))).unwrap_err();
        assert!(e.contains("same file"), "{e}");
        let sub = d.join("sub");
        fs::create_dir(&sub).unwrap();
        let e = Outputs::plan_files(&[("-o", &a), ("--png", &sub.join("../a.exr"))]).unwrap_err();
        assert!(e.contains("same file"), "{e}");
    }

    #[test]
    fn missing_or_unwritable_directories_fail_at_plan_time() {
        let d = dir("missing");
        let e = Outputs::plan(&d.join("no/such/dir/x.exr"), None).unwrap_err();
        assert!(
            e.starts_with("-o ") && e.contains("cannot write in directory"),
            "{e}"
        );
        let e = Outputs::plan(&d, None).unwrap_err();
        assert!(e.contains("is a directory"), "{e}");
        assert!(names(&d).is_empty(), "the probe file is removed");
    }

    #[test]
    fn symlink_target_is_replaced_and_the_link_kept() {
        let d = dir("symlink");
        fs::write(d.join("target.exr"), "old").unwrap();
        std::os::unix::fs::symlink("target.exr", d.join("link.exr")).unwrap();
        let o = Outputs::plan_files(&[("-o", &d.join("link.exr"))]).unwrap();
        o.commit(vec![text("new")]).unwrap();
        assert!(fs::symlink_metadata(d.join("link.exr"))
            .unwrap()
            .file_type()
            .is_symlink());
        assert_eq!(fs::read_to_string(d.join("target.exr")).unwrap(), "new");
        assert_eq!(names(&d), ["link.exr", "target.exr"]);
    }

    #[test]
    fn no_default_png_beside_a_device() {
        assert_eq!(default_png(Path::new("/dev/null")), None);
        assert_eq!(
            default_png(Path::new("some/out.exr")),
            Some(PathBuf::from("some/out.png"))
        );
    }

    #[test]
    fn devices_are_written_not_replaced() {
        let o = Outputs::plan_files(&[("-o", Path::new("/dev/null"))]).unwrap();
        o.commit(vec![text("bytes")]).unwrap();
        use std::os::unix::fs::FileTypeExt;
        assert!(fs::metadata("/dev/null")
            .unwrap()
            .file_type()
            .is_char_device());
    }

    #[test]
    fn a_failing_writer_leaves_every_destination_as_it_was() {
        let d = dir("fail");
        fs::write(d.join("a.exr"), "old a").unwrap();
        fs::write(d.join("b.png"), "old b").unwrap();
        let (a, b) = (d.join("a.exr"), d.join("b.png"));
        let o = Outputs::plan_files(&[("-o", &a), ("--png", &b)]).unwrap();
        let failing: Writer = Box::new(|p: &Path| {
            fs::write(p, "half").unwrap();
            Err("disk full".to_string())
        });
        let e = o.commit(vec![text("new a"), failing]).unwrap_err();
        assert_eq!(
            e,
            OutputError::Bad(format!("--png {}: disk full", b.display()))
        );
        assert_eq!(fs::read_to_string(&a).unwrap(), "old a");
        assert_eq!(fs::read_to_string(&b).unwrap(), "old b");
        assert_eq!(names(&d), ["a.exr", "b.png"]);
    }
}
