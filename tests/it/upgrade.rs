//! `photon upgrade`: pbrt-v3 snippets, each rule's pbrt-v4 text asserted, and the upgraded
//! scene loaded by photon's own loader.
use crate::support::{photon, TempDir};
use photon::scene::upgrade::{Upgraded, Upgrader};
use std::path::PathBuf;
use std::sync::Arc;

/// The camera, film and light of a small v3 scene; `world` follows WorldBegin.
fn v3_scene(world: &str) -> String {
    format!(
        r#"LookAt 0 1 3.5  0 1 0  0 1 0
Camera "perspective" "float fov" [ 45 ]
Film "image" "integer xresolution" [ 8 ] "integer yresolution" [ 8 ] "float scale" 2
Sampler "lowdiscrepancy" "integer pixelsamples" 4
WorldBegin
AttributeBegin
  AreaLightSource "area" "color L" [ 5 5 5 ] "integer nsamples" 4
  Shape "trianglemesh" "point P" [ -0.3 1.99 -0.3  0.3 1.99 -0.3  0.3 1.99 0.3 ]
    "integer indices" [ 0 1 2 ]
AttributeEnd
{world}
WorldEnd
"#
    )
}

/// A square at height `y` (v3 syntax).
fn quad(y: f32) -> String {
    format!(
        "Shape \"trianglemesh\" \"point P\" [ -1 {y} -1  1 {y} -1  1 {y} 1  -1 {y} 1 ] \
         \"integer indices\" [ 0 1 2 0 2 3 ]"
    )
}

fn upgrade(src: &str) -> Upgraded {
    Upgrader::new()
        .upgrade_text(src, Arc::new(PathBuf::from("old.pbrt")))
        .unwrap_or_else(|e| panic!("upgrade failed: {e}"))
}

/// Upgrades `src`, asserts each fragment is in the result, and loads it with photon's loader
/// (in `dir`, beside any files the scene names).
fn upgrade_and_load(dir: &TempDir, src: &str, want: &[&str]) -> Upgraded {
    let up = upgrade(src);
    for w in want {
        assert!(up.text.contains(w), "missing {w:?} in:\n{}", up.text);
    }
    let path = dir.write("new.pbrt", &up.text);
    if let Err(e) = photon::scene::loader::load(&path) {
        panic!("the upgraded scene does not load: {e}\n{}", up.text);
    }
    up
}

#[test]
fn header_film_sampler_area_light_and_triangle_follow_pbrt_v4() {
    let dir = TempDir::new("photon-upgrade-header");
    let up = upgrade_and_load(
        &dir,
        &v3_scene(&quad(0.0)),
        &[
            "Film \"rgb\"\n    \"float iso\" [ 200 ]\n    \"integer xresolution\" [ 8 ]\n",
            "Sampler \"paddedsobol\"\n",
            "LookAt 0 1 3.5  0 1 0  0 1 0\n",
            "    AreaLightSource \"diffuse\"\n        \"rgb L\" [ 5 5 5 ]\n",
            // A lone triangle's [0 1 2] indices go; a quad's stay.
            "    Shape \"trianglemesh\"\n        \"point3 P\" [ -0.3 1.99 -0.3 0.3 1.99 -0.3 0.3 1.99 0.3 ]\nAttributeEnd\n",
            "\"integer indices\" [ 0 1 2 0 2 3 ]",
        ],
    );
    assert!(!up.text.contains("nsamples"), "{}", up.text);
    assert!(!up.text.contains("WorldEnd"), "{}", up.text);
    assert!(up.warnings.is_empty(), "{:?}", up.warnings);
}

#[test]
fn materials_follow_pbrt_v4() {
    let dir = TempDir::new("photon-upgrade-materials");
    let world = format!(
        r#"Material "plastic" "color Kd" [ .4 .2 .1 ] "color Ks" [ .3 .3 .3 ] "float roughness" .1
{q0}
Material "plastic" "color Kd" [ .5 .5 .5 ] "color Ks" [ 0 0 0 ] "float roughness" .1
{q1}
Material "uber" "color Kd" [ .2 .3 .4 ] "color Ks" [ 0 0 0 ] "color opacity" [ 1 1 1 ] "float index" 1.3
{q2}
Material "matte" "color Kd" [ .7 .7 .7 ] "float sigma" 0
{q3}
Material "metal" "float roughness" .01 "color Kr" [ 1 1 1 ]
{q4}
Material "glass" "float index" 1.45 "color Kr" [ 1 1 1 ] "color Kt" [ 1 1 1 ]
{q5}
Material "mirror" "color Kr" [ 0 0 0 ]
{q6}
Material "substrate" "color Kd" [ .3 .3 .3 ] "color Ks" [ 1 1 1 ] "float uroughness" .2 "float vroughness" .2
{q7}
"#,
        q0 = quad(0.0),
        q1 = quad(0.1),
        q2 = quad(0.2),
        q3 = quad(0.3),
        q4 = quad(0.4),
        q5 = quad(0.5),
        q6 = quad(0.6),
        q7 = quad(0.7),
    );
    let up = upgrade_and_load(
        &dir,
        &v3_scene(&world),
        &[
            "# photon upgrade: parameter dropped in the conversion to \"coateddiffuse\": \"rgb Ks\" [ 0.3 0.3 0.3 ]\n\
             Material \"coateddiffuse\"\n    \"rgb reflectance\" [ 0.4 0.2 0.1 ]\n    \"float roughness\" [ 0.1 ]\n",
            // Ks 0: plain diffuse, roughness gone.
            "Material \"diffuse\"\n    \"rgb reflectance\" [ 0.5 0.5 0.5 ]\nShape",
            // uber: opaque opacity dropped; Ks 0 makes it diffuse, and its eta (from index)
            // goes too (pbrt-v4 leaves that eta on the diffuse material).
            "Material \"diffuse\"\n    \"rgb reflectance\" [ 0.2 0.3 0.4 ]\nShape",
            "Material \"diffuse\"\n    \"rgb reflectance\" [ 0.7 0.7 0.7 ]\nShape",
            "Material \"conductor\"\n    \"float roughness\" [ 0.01 ]\nShape",
            "Material \"dielectric\"\n    \"float eta\" [ 1.45 ]\nShape",
            "Material \"conductor\"\n    \"float roughness\" [ 0 ]\n    \"spectrum eta\" [ \"metal-Ag-eta\" ]\n    \"spectrum k\" [ \"metal-Ag-k\" ]\nShape",
            "Material \"coateddiffuse\"\n    \"rgb reflectance\" [ 0.3 0.3 0.3 ]\n    \"float uroughness\" [ 0.2 ]\n    \"float vroughness\" [ 0.2 ]\nShape",
        ],
    );
    // Only the plastic's non-zero Ks was lost.
    let lost: Vec<String> = up.warnings.iter().map(|w| w.to_string()).collect();
    assert_eq!(lost.len(), 1, "{lost:?}");
    assert!(
        lost[0].starts_with("old.pbrt:11:44: parameter dropped"),
        "{lost:?}"
    );
}

#[test]
fn transform_begin_textures_named_materials_and_infinite_light() {
    let dir = TempDir::new("photon-upgrade-textures");
    image::RgbImage::from_pixel(4, 4, image::Rgb([200, 100, 50]))
        .save(dir.0.join("grid.png"))
        .unwrap();
    let world = format!(
        r#"LightSource "infinite" "string mapname" "grid.png" "color L" [ .5 .5 .5 ] "color scale" [ 3 3 3 ] "integer samples" 8
# the textured floor
TransformBegin
  Translate 0 0.5 0
  Texture "g" "color" "imagemap" "string filename" "grid.png" "float gamma" 2.2 "bool trilinear" "true"
  Texture "g" "color" "scale" "texture tex1" "g" "color tex2" [ .5 .5 .5 ]
  MakeNamedMaterial "floor" "string type" "matte" "texture Kd" "g"
  MakeNamedMaterial "floor" "string type" "matte" "color Kd" [ .1 .2 .3 ]
  NamedMaterial "floor"
  {q}
TransformEnd
"#,
        q = quad(0.0)
    );
    let up = upgrade_and_load(
        &dir,
        &v3_scene(&world),
        &[
            "# photon upgrade: pbrt-v4 reads \"grid.png\" as an equal-area (square) map; a pbrt-v3 \
             latitude-longitude map needs converting (pbrt-v4's `imgtool makeequiarea`)\n\
             LightSource \"infinite\"\n    \"float scale\" [ 1.5 ]\n    \"string filename\" [ \"grid.png\" ]\n# the textured floor\nAttributeBegin\n",
            "    Texture \"g\" \"spectrum\" \"imagemap\"\n        \"string filter\" [ \"trilinear\" ]\n        \"string encoding\" [ \"gamma 2.2\" ]\n        \"string filename\" [ \"grid.png\" ]\n",
            // The second "g" is renamed; it scales the first.
            "    Texture \"g-renamed-0\" \"spectrum\" \"scale\"\n        \"texture tex\" [ \"g\" ]\n        \"float scale\" [ 0.5 ]\n",
            "    MakeNamedMaterial \"floor\"\n        \"string type\" [ \"diffuse\" ]\n        \"texture reflectance\" [ \"g-renamed-0\" ]\n",
            "    MakeNamedMaterial \"floor-renamed-0\"\n        \"string type\" [ \"diffuse\" ]\n        \"rgb reflectance\" [ 0.1 0.2 0.3 ]\n",
            "    NamedMaterial \"floor-renamed-0\"\n",
            "AttributeEnd\n",
        ],
    );
    assert!(!up.text.contains("TransformBegin") && !up.text.contains("integer samples"));
    let warned: Vec<String> = up.warnings.iter().map(|w| w.to_string()).collect();
    for w in [
        "old.pbrt:13:1: rewriting \"TransformBegin\" to \"AttributeBegin\"",
        "old.pbrt:16:3: g: renaming multiply-defined texture",
        "old.pbrt:18:3: floor: renaming multiply-defined named material",
        "old.pbrt:21:1: rewriting \"TransformEnd\" to \"AttributeEnd\"",
    ] {
        assert!(warned.iter().any(|x| x == w), "no {w:?} in {warned:?}");
    }
}

#[test]
fn removed_and_unknown_directives() {
    let dir = TempDir::new("photon-upgrade-removed");
    let world = format!(
        "{}\nSurfaceIntegrator \"directlighting\" \"integer maxdepth\" 3",
        quad(0.0)
    );
    let src = v3_scene(&world).replace(
        "WorldBegin",
        "Integrator \"directlighting\" \"integer maxdepth\" 5 \"float rrthreshold\" 0.5\n\
         PixelFilter \"gaussian\" \"float xwidth\" 2 \"float ywidth\" 2 \"float alpha\" 2\nWorldBegin",
    );
    let up = upgrade_and_load(
        &dir,
        &src,
        &[
            "# photon upgrade: dropped \"integer maxdepth\" [ 5 ] of \"directlighting\"\n\
             Integrator \"path\"\n    \"integer maxdepth\" [ 1 ]\nPixelFilter",
            "PixelFilter \"gaussian\"\n    \"float xradius\" [ 2 ]\n    \"float yradius\" [ 2 ]\n    \"float sigma\" [ 0.5 ]\n",
            "# photon upgrade: \"SurfaceIntegrator\" is pbrt-v2 syntax that pbrt-v4 does not read; kept as a comment\n\
             # SurfaceIntegrator \"directlighting\"\n#     \"integer maxdepth\" [ 3 ]\n",
        ],
    );
    assert!(
        up.warnings.iter().any(|w| w
            .to_string()
            .starts_with("old.pbrt:14:1: \"SurfaceIntegrator\" is pbrt-v2")),
        "{:?}",
        up.warnings
    );

    // An unknown directive and what pbrt-v4 refuses to upgrade are one located error.
    let bad = |src: &str| {
        Upgrader::new()
            .upgrade_text(src, Arc::new(PathBuf::from("old.pbrt")))
            .unwrap_err()
            .to_string()
    };
    assert_eq!(
        bad("WorldBegin\n  Frobnicate 1\n"),
        "old.pbrt:2:3: unknown directive \"Frobnicate\""
    );
    assert!(
        bad("WorldBegin\nMaterial \"uber\" \"color opacity\" [ .5 .5 .5 ]\n")
            .starts_with("old.pbrt:2:1: a non-opaque \"opacity\"")
    );
    assert!(bad("LightSource \"point\" \"color scale\" [ 1 2 3 ]\n")
        .starts_with("old.pbrt:1:21: in pbrt-v4 \"scale\" is a \"float\""));
}

#[test]
fn command_writes_the_file_and_warns_on_stderr() {
    let dir = TempDir::new("photon-upgrade-cli");
    let old = dir.write(
        "old.pbrt",
        v3_scene(&format!("TransformBegin\n{}\nTransformEnd", quad(0.0))),
    );
    let new = dir.0.join("new.pbrt");
    let out = photon()
        .args([
            "upgrade",
            old.to_str().unwrap(),
            "-o",
            new.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(out.stdout.is_empty());
    let first = stderr.lines().next().unwrap_or_default();
    assert_eq!(
        first,
        format!(
            "{}:11:1: warning: rewriting \"TransformBegin\" to \"AttributeBegin\"",
            old.display()
        )
    );
    let text = std::fs::read_to_string(&new).unwrap();
    assert!(
        text.contains("\nAttributeBegin\n    Shape \"trianglemesh\"\n"),
        "{text}"
    );
    let check = photon()
        .args(["check", new.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(check.status.success(), "{check:?}");

    // Without -o the text goes to stdout; a syntax error is one located line, exit 2.
    let out = photon()
        .args(["upgrade", old.to_str().unwrap()])
        .output()
        .unwrap();
    assert_eq!(String::from_utf8_lossy(&out.stdout), text);
    let bad = dir.write(
        "bad.pbrt",
        "WorldBegin\nShape \"sphere\" \"float radius\" [ 1\n",
    );
    let out = photon()
        .args(["upgrade", bad.to_str().unwrap()])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(stderr.contains("bad.pbrt:"), "{stderr}");
}
