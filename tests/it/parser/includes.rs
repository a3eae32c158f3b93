//! `Include` / `Import`: missing files, errors located in included files, cycles, and gzipped
//! scenes and PLY files (including a gzip bomb).

use super::*;

#[test]
fn error_includes() {
    let dir = TempDir::new("photon-parser");
    let main = dir.write("scene.pbrt", "WorldBegin\n\nInclude \"missing.pbrt\"\n");
    assert_err(
        load(&main),
        "scene.pbrt",
        3,
        &["missing.pbrt", "cannot read"],
    );
    // An error inside an included file names that file and its line.
    dir.write(
        "parts/inc.pbrt",
        "# part\nAttributeBegin\n  Shape \"cone\"\nAttributeEnd\n",
    );
    let main = dir.write("scene2.pbrt", "WorldBegin\nInclude \"parts/inc.pbrt\"\n");
    assert_err(
        load(&main),
        "parts/inc.pbrt",
        3,
        &["unsupported shape type \"cone\""],
    );
    // A cycle stops at the depth limit, at an Include line.
    let main = dir.write("loop.pbrt", "WorldBegin\nImport \"loop2.pbrt\"\n");
    dir.write("loop2.pbrt", "\nInclude \"loop3.pbrt\"\n");
    dir.write("loop3.pbrt", "Include \"loop2.pbrt\"\n");
    let e = load(&main).unwrap_err();
    assert!(e.msg.contains("nested more than"), "{e}");
    // A missing main file is an error (without a line).
    assert!(load(&dir.0.join("nope.pbrt"))
        .unwrap_err()
        .msg
        .contains("nope.pbrt"));
}

/// Writes `bytes` gzipped (flate2, default level) as `name` in `dir`.
fn write_gz(dir: &TempDir, name: &str, bytes: &[u8]) -> PathBuf {
    use std::io::Write;
    let mut enc = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::default());
    enc.write_all(bytes).unwrap();
    dir.write(name, enc.finish().unwrap())
}

/// `Include "x.pbrt.gz"` and `plymesh` `"x.ply.gz"` load exactly as the plain files.
#[test]
fn gzip_include_and_ply() {
    let dir = TempDir::new("photon-parser");
    let part = format!("Material \"diffuse\" \"rgb reflectance\" [ 0.2 0.3 0.4 ]\n{TRI}\n");
    dir.write("part.pbrt", &part);
    write_gz(&dir, "part.pbrt.gz", part.as_bytes());
    let verts = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [1.0, 1.0, 0.5],
    ];
    let ply = binary_ply(false, &verts, &[vec![0, 1, 2], vec![1, 3, 2]]);
    dir.write("m.ply", &ply);
    write_gz(&dir, "m.ply.gz", &ply);
    let load_with = |ext: &str| {
        let src = format!(
            "WorldBegin\nInclude \"part.pbrt{ext}\"\nShape \"plymesh\" \"string filename\" \"m.ply{ext}\"\n"
        );
        load(&dir.write(&format!("scene{ext}.pbrt"), src)).unwrap()
    };
    let (plain, gz) = (load_with(""), load_with(".gz"));
    assert_eq!(gz.meshes.len(), 2);
    for (a, b) in plain.meshes.iter().zip(&gz.meshes) {
        assert_eq!((&a.positions, &a.indices), (&b.positions, &b.indices));
    }
    assert_eq!(plain.materials, gz.materials);
    assert_eq!(gz.meshes[1].positions[3], Vec3::new(1.0, 1.0, 0.5));

    // A corrupt .gz: a one-line error naming the file, at the Include / Shape.
    let mut bad = std::fs::read(dir.0.join("part.pbrt.gz")).unwrap();
    let n = bad.len();
    bad[n / 2] ^= 0xff;
    bad.truncate(n - 4);
    dir.write("bad.pbrt.gz", &bad);
    dir.write("bad.ply.gz", b"not gzip at all");
    assert_src_err_in(
        &dir,
        "WorldBegin\n\nInclude \"bad.pbrt.gz\"\n",
        3,
        &["bad.pbrt.gz", "gzip"],
    );
    assert_src_err_in(
        &dir,
        "WorldBegin\nShape \"plymesh\" \"string filename\" \"bad.ply.gz\"\n",
        2,
        &["bad.ply.gz", "gzip"],
    );
}

/// Checks an error of `src` written as `scene.pbrt` in `dir` (so it can name files there).
#[track_caller]
fn assert_src_err_in(dir: &TempDir, src: &str, line: u32, needles: &[&str]) {
    assert_err(
        load(&dir.write("scene.pbrt", src)),
        "scene.pbrt",
        line,
        needles,
    );
}

/// A gzip bomb (10 MB of zeros in ~10 KB) against a 1 MiB cap: a clean error, and the
/// decompressed size is bounded by the cap, not by what the data claims.
#[test]
fn gzip_bomb_is_capped() {
    use photon::scene::loader::gunzip_capped;
    use std::io::Write;
    let mut enc = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::best());
    enc.write_all(&vec![0u8; 10 << 20]).unwrap();
    let bomb = enc.finish().unwrap();
    assert!(bomb.len() < 64 << 10, "{}", bomb.len());
    let e = gunzip_capped(&bomb, 1 << 20).unwrap_err().to_string();
    assert!(
        e.contains("decompresses to more than the limit of 1.0 MB"),
        "{e}"
    );
    assert_eq!(gunzip_capped(&bomb, 10 << 20).unwrap().len(), 10 << 20);
}
