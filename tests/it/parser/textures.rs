//! `Texture`: parsed with pbrt-v4's defaults, one copy per image file, and texture errors.

use super::*;

/// Writes a 2x1 RGB image: left texel (128, 10, 255), right texel (0, 255, 64).
fn write_image(dir: &TempDir, name: &str) {
    let img = image::RgbImage::from_raw(2, 1, vec![128, 10, 255, 0, 255, 64]).unwrap();
    img.save(dir.0.join(name)).unwrap();
}

#[test]
fn textures_are_parsed_with_pbrt_defaults_and_one_copy_per_image() {
    let dir = TempDir::new("photon-parser");
    write_image(&dir, "t.png");
    write_image(&dir, "t.tga");
    let scene = dir.write(
        "scene.pbrt",
        r#"WorldBegin
Texture "a" "spectrum" "imagemap" "string filename" "t.png" "string wrap" "clamp"
Texture "b" "spectrum" "imagemap" "string filename" "t.png" "float uscale" 2 "string filter" "point"
Texture "c" "spectrum" "imagemap" "string filename" "t.tga"
Texture "g" "float" "imagemap" "string filename" "t.png" "string encoding" "gamma 2.2"
Texture "half" "float" "constant" "float value" 0.5
Texture "s" "spectrum" "scale" "texture tex" "c" "texture scale" "half"
Texture "m" "spectrum" "mix" "texture tex1" "c" "rgb tex2" [ 0 0 1 ] "float amount" 0.25
Texture "k" "spectrum" "checkerboard" "rgb tex1" [ 1 1 1 ] "texture tex2" "s"
    "float uscale" 4 "float vscale" 4
"#,
    );
    let s = load(&scene).unwrap();
    let (sp, fl) = (&s.textures.spectrum, &s.textures.float);
    assert_eq!((sp.len(), fl.len()), (6, 2));
    let at = |t: &photon::texture::Texture, u: f32| t.eval(Vec2::new(u, 0.5));
    // PNG defaults to sRGB: 128 -> 0.215861, 10 -> 10 / 255 / 12.92, 255 -> 1 (IEC 61966-2-1).
    let left_srgb = Vec3::new(0.215861, 10.0 / 255.0 / 12.92, 1.0);
    assert_vec(at(&sp["a"], 0.25), left_srgb, 1e-5);
    // Clamp: u = 0 is the left texel's centre's left half, still the left texel.
    assert_vec(at(&sp["a"], 0.0), left_srgb, 1e-5);
    // uscale 2 with point filtering: u = 0.3 -> s = 0.6, the right texel (0, 1, 64 decoded).
    let right_srgb = Vec3::new(0.0, 1.0, 0.051269);
    assert_vec(at(&sp["b"], 0.3), right_srgb, 1e-5);
    // A TGA is sRGB too, as pbrt-v4's Image::Read decodes every 8-bit stb format.
    let left_linear = left_srgb;
    assert_vec(at(&sp["c"], 0.25), left_linear, 1e-5);
    // Float imagemap: the red channel (pbrt-v4's MIPMap::Texel<Float>), gamma-2.2-decoded.
    let g = (128.0f32 / 255.0).powf(2.2);
    assert_vec(at(&fl["g"], 0.25), Vec3::splat(g), 1e-5);
    assert_vec(at(&sp["s"], 0.25), left_linear * 0.5, 1e-5);
    assert_vec(
        at(&sp["m"], 0.25),
        0.75 * left_linear + Vec3::new(0.0, 0.0, 0.25),
        1e-5,
    );
    // Checkerboard 4x4: (u, v) = (0.1, 0.5) -> cell (0, 2), even: tex1; (0.3, 0.5) odd: "s".
    assert_vec(at(&sp["k"], 0.1), Vec3::ONE, 0.0);
    assert_vec(at(&sp["k"], 0.3), at(&sp["s"], 0.3), 0.0);
    // "a" and "b" share one decoded t.png (same encoding); "g" decoded it separately.
    let image = |t: &photon::texture::Texture| match t {
        photon::texture::Texture::Image(m) => m.image.clone(),
        other => panic!("not an image texture: {other:?}"),
    };
    assert!(std::sync::Arc::ptr_eq(&image(&sp["a"]), &image(&sp["b"])));
    assert!(!std::sync::Arc::ptr_eq(&image(&sp["a"]), &image(&fl["g"])));
}

#[test]
fn texture_errors() {
    let dir = TempDir::new("photon-parser");
    write_image(&dir, "t.png");
    let err = |body: &str| {
        let p = dir.write("scene.pbrt", format!("WorldBegin\n{body}\n"));
        load(&p).unwrap_err().to_string()
    };
    let e = err(r#"Texture "a" "spectrum" "imagemap" "string filename" "nope.png""#);
    assert!(
        e.contains("scene.pbrt:2:24: imagemap") && e.contains("nope.png"),
        "{e}"
    );
    let e = err(r#"Texture "a" "color" "constant""#);
    assert!(e.contains("\"spectrum\" or \"float\""), "{e}");
    let e = err(r#"Texture "a" "spectrum" "scale" "texture tex" "missing""#);
    assert!(e.contains("unknown spectrum texture \"missing\""), "{e}");
    // Namespaces: a float texture is not a spectrum texture.
    let e = err("Texture \"f\" \"float\" \"constant\"\nTexture \"a\" \"spectrum\" \"scale\" \"texture tex\" \"f\"");
    assert!(e.contains("unknown spectrum texture \"f\""), "{e}");
    let e = err("Texture \"f\" \"float\" \"constant\"\nTexture \"f\" \"float\" \"constant\"");
    assert!(
        e.contains("scene.pbrt:3:9: float texture \"f\" redefined"),
        "{e}"
    );
    let e = err(r#"Texture "a" "spectrum" "checkerboard" "integer dimension" 3"#);
    assert!(e.contains("only 2D checkerboards"), "{e}");
    let e = err(r#"Texture "a" "spectrum" "checkerboard" "string mapping" "spherical""#);
    assert!(
        e.contains("unsupported texture mapping \"spherical\""),
        "{e}"
    );
    let e = err(
        r#"Texture "a" "spectrum" "imagemap" "string filename" "t.png" "string wrap" "mirror""#,
    );
    assert!(
        e.contains("\"mirror\" is not repeat, clamp or black"),
        "{e}"
    );
    let e = err(
        r#"Texture "a" "spectrum" "imagemap" "string filename" "t.png" "string encoding" "gamma x""#,
    );
    assert!(e.contains("is not an encoding"), "{e}");
    let e = err(r#"Texture "a" "spectrum" "wrinkled""#);
    assert!(e.contains("unsupported texture class \"wrinkled\""), "{e}");
    let e = err(r#"Texture "a" "spectrum" "constant" "float uscale" 2"#);
    assert!(e.contains("unused parameter \"float uscale\""), "{e}");
    // A float texture where a spectrum one is wanted, and the other way round.
    let e = err(
        "Texture \"a\" \"float\" \"constant\"\nMaterial \"diffuse\" \"texture reflectance\" \"a\"",
    );
    assert!(
        e.contains(
            "scene.pbrt:3:20: parameter \"texture reflectance\": unknown spectrum texture \"a\""
        ),
        "{e}"
    );
    let e = err("Texture \"a\" \"spectrum\" \"constant\"\nMaterial \"conductor\" \"texture roughness\" \"a\"");
    assert!(e.contains("unknown float texture \"a\""), "{e}");
    // A light's colour cannot be a texture.
    let e =
        err("Texture \"a\" \"spectrum\" \"constant\"\nLightSource \"point\" \"texture I\" \"a\"");
    assert!(
        e.contains("\"texture I\": a texture is not supported for this parameter"),
        "{e}"
    );
}
