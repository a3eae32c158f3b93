//! `photon upgrade OLD.pbrt [-o NEW.pbrt] [--recursive]`: translates a pbrt-v3 scene file into
//! pbrt-v4 syntax by the rules of pbrt-v4's `pbrt --upgrade` ([`crate::scene::upgrade`]).
//!
//! ```text
//! $ photon upgrade old/scene.pbrt -o new/scene.pbrt
//! old/scene.pbrt:12:1: warning: rewriting "TransformBegin" to "AttributeBegin"
//! old/scene.pbrt:30:5: warning: parameter dropped in the conversion to "coateddiffuse": "rgb Ks" [ 0.25 0.25 0.25 ]
//! ```
//!
//! The pbrt-v4 text goes to standard output, or to `-o` (written to a temporary beside it and
//! renamed into place, [`super::output`]). Each warning is one line on standard error with its
//! `file:line:column`; an error (what pbrt-v4 also refuses to upgrade, a syntax error) is one
//! line, exit code 2, and nothing is written.
//!
//! `Include` and `Import` statements are kept as written and the files they name are left
//! alone; with `--recursive` they are upgraded too (and the files they include, each once),
//! each written under the name the statement gives, relative to the folder of `-o` (which
//! `--recursive` needs, and which must not be the scene's own folder: the pbrt-v3 files would
//! be overwritten).

use super::output::{Outputs, Writer};
use super::ToolError;
use crate::scene::loader::read_input;
use crate::scene::upgrade::{Upgraded, Upgrader};
use crate::scene::SceneError;
use clap::Args;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// `photon upgrade` options.
#[derive(Args, Debug, Clone)]
pub struct UpgradeOptions {
    /// The pbrt-v3 scene file (`.pbrt` or `.pbrt.gz`).
    pub scene: PathBuf,
    /// Where to write the pbrt-v4 scene (standard output when not given).
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// Upgrade the files named by `Include` and `Import` too, writing each under its name
    /// relative to the folder of `-o` (needed, and not the scene's own folder).
    #[arg(long)]
    pub recursive: bool,
}

/// Reads and upgrades one file.
fn upgrade_one(
    up: &mut Upgrader,
    path: &Path,
    from: Option<&SceneError>,
) -> Result<Upgraded, ToolError> {
    let bytes = read_input(path, crate::limits::MAX_SCENE_FILE).map_err(|e| {
        let msg = format!("cannot read \"{}\": {e}", path.display());
        match from.and_then(|f| f.loc.as_ref()) {
            Some(loc) => ToolError(SceneError::at(loc, msg).to_string()),
            None => ToolError(msg),
        }
    })?;
    let text = String::from_utf8(bytes).map_err(|e| {
        ToolError(format!(
            "{}: not UTF-8 text (byte {})",
            path.display(),
            e.utf8_error().valid_up_to()
        ))
    })?;
    Ok(up.upgrade_text(&text, Arc::new(path.to_path_buf()))?)
}

/// Upgrades the scene (and with `--recursive` what it includes) and writes the result.
pub fn run(opts: &UpgradeOptions) -> Result<(), ToolError> {
    if opts.recursive && opts.output.is_none() {
        return Err(ToolError(
            "--recursive needs -o: the included files are written beside it".into(),
        ));
    }
    let mut up = Upgrader::new();
    let main = upgrade_one(&mut up, &opts.scene, None)?;
    // (source, destination relative to the output folder, upgraded text)
    let mut files: Vec<(PathBuf, PathBuf, Upgraded)> = Vec::new();
    let scene_dir = opts.scene.parent().unwrap_or(Path::new("")).to_path_buf();
    if opts.recursive {
        let mut queue: Vec<(String, SceneError)> = main
            .includes
            .iter()
            .map(|(n, l)| (n.clone(), SceneError::at(l, "")))
            .collect();
        let mut seen: Vec<PathBuf> = vec![opts.scene.clone()];
        while !queue.is_empty() {
            let (name, from) = queue.remove(0);
            let rel = PathBuf::from(&name);
            let at = |msg: String| match &from.loc {
                Some(l) => ToolError(SceneError::at(l, msg).to_string()),
                None => ToolError(msg),
            };
            if rel.is_absolute()
                || rel
                    .components()
                    .any(|c| c == std::path::Component::ParentDir)
            {
                return Err(at(format!(
                    "--recursive: \"{name}\" is not a path inside the scene's folder; upgrade it separately"
                )));
            }
            let src = scene_dir.join(&rel);
            if seen.contains(&src) {
                continue;
            }
            seen.push(src.clone());
            let done = upgrade_one(&mut up, &src, Some(&from))?;
            queue.extend(
                done.includes
                    .iter()
                    .map(|(n, l)| (n.clone(), SceneError::at(l, ""))),
            );
            files.push((src, rel, done));
        }
    }
    for w in main
        .warnings
        .iter()
        .chain(files.iter().flat_map(|f| f.2.warnings.iter()))
    {
        say_err!("{}", warning_line(w));
    }
    let Some(out) = &opts.output else {
        say_part!("{}", main.text);
        return Ok(());
    };
    let out_dir = out.parent().unwrap_or(Path::new("")).to_path_buf();
    let mut planned: Vec<(String, PathBuf)> = vec![("-o".to_string(), out.clone())];
    for (src, rel, _) in &files {
        let dest = out_dir.join(rel);
        if same_file(src, &dest) {
            return Err(ToolError(format!(
                "--recursive: writing {} would overwrite the pbrt-v3 file; give -o a path in another folder",
                dest.display()
            )));
        }
        if let Some(dir) = dest.parent() {
            std::fs::create_dir_all(dir)
                .map_err(|e| ToolError(format!("{}: {e}", dir.display())))?;
        }
        planned.push(("--recursive".to_string(), dest));
    }
    let pairs: Vec<(&str, &Path)> = planned
        .iter()
        .map(|(f, p)| (f.as_str(), p.as_path()))
        .collect();
    let outputs = Outputs::plan_files(&pairs).map_err(ToolError)?;
    let texts: Vec<&str> = std::iter::once(main.text.as_str())
        .chain(files.iter().map(|f| f.2.text.as_str()))
        .collect();
    let writers: Vec<Writer> = texts
        .into_iter()
        .map(|t| -> Writer {
            Box::new(move |p: &Path| std::fs::write(p, t).map_err(|e| e.to_string()))
        })
        .collect();
    outputs.commit(writers)?;
    Ok(())
}

/// `file:line:column: warning: what`.
fn warning_line(w: &SceneError) -> String {
    match &w.loc {
        Some(loc) => format!("{loc}: warning: {}", w.msg),
        None => format!("warning: {}", w.msg),
    }
}

/// Whether `a` and `b` name one existing file.
fn same_file(a: &Path, b: &Path) -> bool {
    match (a.canonicalize(), b.canonicalize()) {
        (Ok(x), Ok(y)) => x == y,
        _ => false,
    }
}
