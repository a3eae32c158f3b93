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
//! the file they name (photon follows the last component's links itself, so it applies the
//! kernel's `fs.protected_symlinks` rule itself: a link in a sticky directory such as /tmp that
//! is owned by another user than the process's effective uid is refused, not followed; links
//! elsewhere, and one's own, are followed), refuses directories, sockets and block devices,
//! refuses two outputs that
//! are the same file (and `-o` with a `.png` extension, which the preview would overwrite), and
//! proves each regular destination's directory writable by creating and removing a probe file.
//! [`Outputs::commit`] (or [`Outputs::write`] for a render's EXR and PNG) writes every file to
//! a hidden temporary beside its destination (`.NAME.<pid>.photon-tmp.EXT`) and renames them
//! all only when every one is complete; a character device or a FIFO gets the finished bytes
//! copied in, never a rename, so `/dev/null` stays a device (devices and FIFOs are written
//! first, then the renames: a FIFO nobody reads cannot leave the other outputs replaced). It
//! installs the SIGINT/SIGTERM flag ([`crate::interrupt`]) for the writing phase and polls it
//! after each file, and while a FIFO or device is opened and written (in a thread: opening a
//! FIFO blocks until a reader comes): on a signal the temporaries are removed, nothing is
//! renamed, and [`OutputError::Interrupted`] tells the caller which exit code to use (130/143).
//!
//! When a destination cannot take its finished file at the end (its folder removed or made
//! read-only during the render, the disk full, `-o /dev/full`), the work is not thrown away:
//! every file not yet in place is written again to a fallback, `photon-<pid>-NAME` in the
//! system's temporary directory (else in the working directory), created exclusively, and the
//! error says where ("... saved to PATH instead"); the exit code stays 2.
//! [`Outputs::keep_elsewhere`] writes there directly (a render stopped by a signal keeps its
//! finished tiles so, leaving its outputs as they were).
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
    /// The format of the first file (a render's `-o`): see [`ImageFormat::of`].
    pub format: ImageFormat,
}

/// The format of a rendered image, chosen by `-o`'s extension as pbrt-v4 does.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImageFormat {
    /// Linear OpenEXR with the component layers (and the default PNG preview beside it).
    Exr,
    /// 8-bit sRGB PNG only (`--exposure` applies).
    Png,
    /// Linear float PFM (RGB only, as pbrt-v4 writes it).
    Pfm,
}

impl ImageFormat {
    /// The format `path` names by its extension (any case): `.exr`, `.png`, `.pfm`; a path
    /// without one, or a device or FIFO whatever its name (`/dev/null`, `out.fifo`), is EXR;
    /// any other extension is an error naming `flag`.
    pub fn of(flag: &str, path: &Path) -> Result<ImageFormat, String> {
        if default_png(path).is_none() {
            return Ok(ImageFormat::Exr); // a device or FIFO: no extension rule
        }
        let ext = path
            .extension()
            .map(|e| e.to_string_lossy().to_ascii_lowercase());
        match ext.as_deref() {
            None | Some("exr") => Ok(ImageFormat::Exr),
            Some("png") => Ok(ImageFormat::Png),
            Some("pfm") => Ok(ImageFormat::Pfm),
            Some(other) => Err(format!(
                "{flag} {}: unknown image format \".{}\" (photon writes .exr, .png and .pfm)",
                path.display(),
                crate::scene::clip_for_message(other, 16)
            )),
        }
    }
}

/// A writer of one output into the path it is given (called again for the fallback file when
/// the destination fails).
pub type Writer<'a> = Box<dyn Fn(&Path) -> Result<(), String> + 'a>;

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

/// The process's effective uid, from `/proc/self/status` (`None` where it cannot be read).
fn effective_uid() -> Option<u32> {
    let status = fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("Uid:"))?;
    line.split_whitespace().nth(2)?.parse().ok()
}

/// `S_ISVTX`: the sticky bit of a directory's mode.
const STICKY: u32 = 0o1000;

/// Refuses to follow the symlink `link` (metadata `m`) when it lives in a sticky directory and
/// is owned by another user than this process's effective uid (an unknown uid counts as
/// another): Linux's `fs.protected_symlinks` rule, which the kernel cannot apply here because
/// photon reads the link itself.
fn check_link_owner(link: &Path, m: &fs::Metadata) -> Result<(), String> {
    use std::os::unix::fs::MetadataExt;
    let sticky = fs::metadata(dir_of(link)).is_ok_and(|d| d.mode() & STICKY != 0);
    let me = effective_uid();
    if sticky && me != Some(m.uid()) {
        return Err(format!(
            "a symlink owned by uid {} in a sticky directory is not followed (photon runs as uid {})",
            m.uid(),
            me.map_or("unknown".to_string(), |u| u.to_string())
        ));
    }
    Ok(())
}

/// `path` with every symlink in its last component followed (a dangling link names the file
/// to create); another user's link in a sticky directory is refused ([`check_link_owner`]).
fn follow_links(path: &Path) -> Result<PathBuf, String> {
    let mut p = path.to_path_buf();
    for _ in 0..MAX_LINKS {
        match fs::symlink_metadata(&p) {
            Ok(m) if m.file_type().is_symlink() => {
                check_link_owner(&p, &m)?;
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
        Ok(Outputs {
            files: planned,
            format: ImageFormat::Exr,
        })
    }

    /// The outputs of a partial image (`render --passes`, `merge`): the EXR (`-o`), which
    /// keeps the sums and counts, and the optional PNG preview of its mean (`--png`).
    pub fn plan(exr: &Path, png: Option<&Path>) -> Result<Outputs, String> {
        if ImageFormat::of("-o", exr)? != ImageFormat::Exr {
            return Err(format!(
                "-o {}: a partial image (--passes, --progressive, merge) is an EXR; the PNG preview goes to --png",
                exr.display()
            ));
        }
        let mut files = vec![("-o", exr)];
        files.extend(png.map(|p| ("--png", p)));
        Outputs::plan_files(&files)
    }

    /// A finished render's outputs: `-o` in the format its extension names (see
    /// [`ImageFormat::of`]) and the optional PNG preview (`--png`).
    pub fn plan_image(image: &Path, png: Option<&Path>) -> Result<Outputs, String> {
        let format = ImageFormat::of("-o", image)?;
        let mut files = vec![("-o", image)];
        files.extend(png.map(|p| ("--png", p)));
        let mut planned = Outputs::plan_files(&files)?;
        planned.format = format;
        Ok(planned)
    }

    /// Writes each file with its writer (one per planned file, in order) to a temporary, then
    /// puts them all in place. On a signal the temporaries are removed and no destination is
    /// touched. On an error the files not yet in place are written to fallbacks (see the
    /// module) and the error says where.
    pub fn commit(&self, writers: Vec<Writer>) -> Result<(), OutputError> {
        self.commit_with(writers, true)
    }

    /// [`Self::commit`] without fallbacks: for a file that is written again later anyway (a
    /// checkpoint).
    pub fn commit_without_fallback(&self, writers: Vec<Writer>) -> Result<(), OutputError> {
        self.commit_with(writers, false)
    }

    fn commit_with(&self, writers: Vec<Writer>, fallback: bool) -> Result<(), OutputError> {
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
        let mut placed = vec![false; self.files.len()];
        let result = self.write_temps(&writers, &temps).and_then(|()| {
            check_signal()?;
            self.place(&temps, &mut placed)
        });
        for t in &temps {
            let _ = fs::remove_file(t);
        }
        match result {
            Err(OutputError::Bad(m)) if fallback => {
                let left: Vec<usize> = (0..placed.len()).filter(|&i| !placed[i]).collect();
                Err(OutputError::Bad(self.fall_back(&writers, &left, &m)))
            }
            r => r,
        }
    }

    /// Runs the writers into the temporaries, polling for a signal after each.
    fn write_temps(&self, writers: &[Writer], temps: &[PathBuf]) -> Result<(), OutputError> {
        for ((f, w), tmp) in self.files.iter().zip(writers).zip(temps) {
            check_signal()?;
            w(tmp)
                .map_err(|m| OutputError::Bad(format!("{} {}: {m}", f.flag, f.shown.display())))?;
        }
        check_signal()
    }

    /// Copies the temporaries of devices and FIFOs into them (interruptible: a FIFO nobody
    /// reads blocks), then renames every other temporary into place; `placed` records which
    /// destinations hold their new file.
    fn place(&self, temps: &[PathBuf], placed: &mut [bool]) -> Result<(), OutputError> {
        let order = (self.files.iter().enumerate())
            .filter(|(_, f)| f.kind == Kind::Special)
            .chain((self.files.iter().enumerate()).filter(|(_, f)| f.kind == Kind::Regular));
        for (i, f) in order {
            let done = match f.kind {
                Kind::Regular => fs::rename(&temps[i], &f.dest),
                Kind::Special => copy_into(&temps[i], &f.dest).map_err(OutputError::Interrupted)?,
            };
            done.map_err(|e| OutputError::Bad(format!("{} {}: {e}", f.flag, f.shown.display())))?;
            placed[i] = true;
        }
        Ok(())
    }

    /// `error` followed by where the files `which` were saved instead (or why they could not
    /// be).
    fn fall_back(&self, writers: &[Writer], which: &[usize], error: &str) -> String {
        if which.is_empty() {
            return error.to_string();
        }
        let (mut saved, mut failed) = (Vec::new(), String::new());
        for &i in which {
            match self.keep_one(&writers[i], &self.files[i]) {
                Ok(p) => saved.push(p.display().to_string()),
                Err(e) => {
                    let f = &self.files[i];
                    failed += &format!("; {} could not be saved elsewhere either: {e}", f.flag);
                }
            }
        }
        let what = if saved.len() == 1 {
            "it was"
        } else {
            "they were"
        };
        match saved.is_empty() {
            true => format!("{error}{failed}"),
            false => format!(
                "{error}; {what} saved to {} instead{failed}",
                saved.join(" and ")
            ),
        }
    }

    /// Writes each planned file with its writer to a fallback (see the module) instead of its
    /// destination; returns the paths written, in order.
    pub fn keep_elsewhere(&self, writers: Vec<Writer>) -> Result<Vec<PathBuf>, String> {
        assert_eq!(writers.len(), self.files.len(), "one writer per output");
        (self.files.iter().zip(&writers))
            .map(|(f, w)| self.keep_one(w, f))
            .collect()
    }

    /// Writes `f`'s content with `w` to a fresh fallback file.
    fn keep_one(&self, w: &Writer, f: &OutputFile) -> Result<PathBuf, String> {
        let name = f.shown.file_name().unwrap_or_default().to_string_lossy();
        let pid = std::process::id();
        let mut last = String::from("no fallback directory");
        let dirs = [std::env::temp_dir(), PathBuf::from(".")];
        for dir in &dirs {
            for k in 0..100 {
                let file = match k {
                    0 => format!("photon-{pid}-{name}"),
                    _ => format!("photon-{pid}-{k}-{name}"),
                };
                let p = dir.join(file);
                // Created exclusively: an existing file (or a link planted there) is skipped.
                match fs::OpenOptions::new().write(true).create_new(true).open(&p) {
                    Ok(_) => {}
                    Err(e) if e.kind() == io::ErrorKind::AlreadyExists => continue,
                    Err(e) => {
                        last = format!("{}: {e}", p.display());
                        break;
                    }
                }
                match w(&p) {
                    Ok(()) => return Ok(fs::canonicalize(&p).unwrap_or(p)),
                    Err(e) => {
                        let _ = fs::remove_file(&p);
                        last = format!("{}: {e}", p.display());
                        break;
                    }
                }
            }
        }
        Err(last)
    }

    /// A render's image (an EXR with its component layers, or the PNG or PFM `-o` names) and
    /// PNG preview, as planned by [`Self::plan_image`].
    pub fn write(
        &self,
        image: &RgbImage,
        layers: &[(&str, &RgbImage)],
        pixel: ExrPixel,
        exposure: f32,
        extra: imageio::ExrExtra,
    ) -> Result<(), OutputError> {
        self.commit(self.render_writers(image, layers, pixel, exposure, extra))
    }

    /// The writers of a render's EXR (with `extra`'s data channels and header attributes) and
    /// PNG preview (for [`Self::commit`] or [`Self::keep_elsewhere`]).
    pub fn render_writers<'a>(
        &self,
        image: &'a RgbImage,
        layers: &'a [(&'a str, &'a RgbImage)],
        pixel: ExrPixel,
        exposure: f32,
        extra: imageio::ExrExtra<'a>,
    ) -> Vec<Writer<'a>> {
        let mut writers: Vec<Writer> = vec![match self.format {
            ImageFormat::Exr => Box::new(move |tmp: &Path| {
                imageio::write_exr_with(tmp, image, layers, pixel, extra).map_err(|e| kind_only(&e))
            }),
            ImageFormat::Png => Box::new(move |tmp: &Path| {
                imageio::write_png(tmp, image, exposure).map_err(|e| kind_only(&e))
            }),
            ImageFormat::Pfm => Box::new(move |tmp: &Path| {
                imageio::write_pfm(tmp, image).map_err(|e| kind_only(&e))
            }),
        }];
        if self.files.len() > 1 {
            writers.push(Box::new(move |tmp: &Path| {
                imageio::write_png(tmp, image, exposure).map_err(|e| kind_only(&e))
            }));
        }
        writers
    }
}

/// An image error without its (temporary) path: the caller names the destination.
pub fn kind_only(e: &imageio::ImageError) -> String {
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
/// truncated or replaced). Opening a FIFO blocks until a reader comes and writing blocks while
/// it does not read, so both run in a thread while this one polls for a signal: on one it
/// returns `Err(signal)` and leaves the thread behind (the process is about to exit; the
/// temporary it reads may be removed meanwhile, as it is already open).
fn copy_into(tmp: &Path, dest: &Path) -> Result<io::Result<()>, Signal> {
    use std::sync::mpsc::{channel, RecvTimeoutError};
    let mut src = match fs::File::open(tmp) {
        Ok(f) => f,
        Err(e) => return Ok(Err(e)),
    };
    let dest = dest.to_path_buf();
    let (tx, rx) = channel();
    std::thread::spawn(move || {
        let done = fs::OpenOptions::new()
            .write(true)
            .open(&dest)
            .and_then(|mut out| io::copy(&mut src, &mut out).map(|_| ()));
        let _ = tx.send(done);
    });
    loop {
        match rx.recv_timeout(std::time::Duration::from_millis(20)) {
            Ok(done) => return Ok(done),
            Err(RecvTimeoutError::Timeout) => {
                if let Some(s) = interrupt::requested() {
                    return Err(s);
                }
            }
            Err(RecvTimeoutError::Disconnected) => {
                return Ok(Err(io::Error::other("the writing thread stopped")))
            }
        }
    }
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
        let e = o
            .commit(vec![text("new a"), failing])
            .unwrap_err()
            .to_string();
        // The EXR's content is kept in a fallback; the failing writer fails there too.
        let prefix = format!("--png {}: disk full; it was saved to ", b.display());
        assert!(e.starts_with(&prefix), "{e}");
        let saved = e[prefix.len()..].split(" instead").next().unwrap();
        assert_eq!(fs::read_to_string(saved).unwrap(), "new a");
        fs::remove_file(saved).unwrap();
        let failed = "; --png could not be saved elsewhere either: ";
        assert!(e.contains(failed) && e.ends_with(": disk full"), "{e}");
        assert_eq!(fs::read_to_string(&a).unwrap(), "old a");
        assert_eq!(fs::read_to_string(&b).unwrap(), "old b");
        assert_eq!(names(&d), ["a.exr", "b.png"]);
    }
}
