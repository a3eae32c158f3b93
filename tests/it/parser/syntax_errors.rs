//! Tokenizer details and the located errors that belong to no one directive: unknown and
//! unsupported directives, parameter types and values, unused parameters, blocks, unterminated
//! strings, media and curves.

use super::*;

#[test]
fn syntax_details() {
    // Comments, bare and quoted bools, single values without brackets, strings with escapes,
    // include and import relative to the main file's directory (also from a subdirectory).
    let dir = TempDir::new("photon-parser");
    dir.write(
        "sub/a.pbrt",
        "# included\nMakeNamedMaterial \"m\" \"string type\" \"diffuse\"\nImport \"sub/b.pbrt\"\n",
    );
    dir.write("sub/b.pbrt", format!("NamedMaterial \"m\"\n{TRI}\n"));
    let scene = dir.write(
        "scene.pbrt",
        format!(
            "Film \"rgb\" \"string filename\" \"a\\\"b.exr\" # comment \"not a string\n\
         WorldBegin # ok\nInclude \"sub/a.pbrt\"\n\
         AreaLightSource \"diffuse\" \"bool twosided\" true\n\
         Shape \"trianglemesh\" \"point P\" [1 0 0 0 1 0 0 0 1]\n\
         AreaLightSource \"diffuse\" \"bool twosided\" [ \"false\" ]\n{TRI}\n"
        ),
    );
    let s = load(&scene).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(s.film.filename.as_deref(), Some("a\"b.exr"));
    assert_eq!(s.meshes.len(), 3);
    assert_eq!(
        s.materials[s.meshes[0].material as usize],
        diffuse(Vec3::splat(0.5))
    );
    assert!(matches!(
        s.lights[0],
        Light::Area {
            two_sided: true,
            ..
        }
    ));
    assert!(matches!(
        s.lights[1],
        Light::Area {
            two_sided: false,
            ..
        }
    ));
    assert_eq!(s.path, scene);
}

#[test]
fn error_unknown_and_unsupported_directives() {
    assert_src_err(
        "WorldBegin\n\n  Shap \"sphere\"\n",
        3,
        &["unknown directive \"Shap\""],
    );
    assert_src_err(
        "WorldBegin\nTexture \"t\" \"spectrum\" \"imagemap\"\n",
        2,
        &["imagemap needs \"string filename\""],
    );
    assert_src_err(
        "WorldBegin\nAttribute \"shape\" \"float radius\" 2\n",
        2,
        &["unsupported directive \"Attribute\""],
    );
    assert_src_err("WorldBegin\nWorldEnd\n", 2, &["\"WorldEnd\""]);
    assert_src_err(
        "WorldBegin\nShape \"hyperboloid\"\n",
        2,
        &["unsupported shape type \"hyperboloid\""],
    );
    assert_src_err(
        "WorldBegin\nMaterial \"hair\"\n",
        2,
        &["unsupported material type \"hair\""],
    );
    assert_src_err(
        "WorldBegin\nMakeNamedMaterial \"x\"\n \"string type\" \"interface\"\nNamedMaterial \"x\"\nShape \"sphere\"\n",
        5,
        &["\"interface\" needs a MediumInterface"],
    );
    assert_src_err(
        "WorldBegin\nLightSource \"goniometric\"\n",
        2,
        &["unsupported light type \"goniometric\""],
    );
    assert_src_err("WorldBegin\nAreaLightSource \"spot\"\n", 2, &["\"spot\""]);
    assert_src_err(
        "Camera \"realistic\"\nWorldBegin\n",
        1,
        &["unsupported camera type \"realistic\""],
    );
    assert_src_err("Film \"spectral\"\nWorldBegin\n", 1, &["\"spectral\""]);
    assert_src_err(
        "PixelFilter \"mitchell\"\nWorldBegin\n",
        1,
        &["\"mitchell\""],
    );
    assert_src_err("Sampler \"magic\"\nWorldBegin\n", 1, &["\"magic\""]);
    assert_src_err("WorldBegin\n[ 1 ]\n", 2, &["expected a directive"]);
    assert_src_err(
        "Shape \"sphere\"\nWorldBegin\n",
        1,
        &["only allowed after WorldBegin"],
    );
    assert_src_err(
        "WorldBegin\nCamera \"perspective\"\n",
        2,
        &["not allowed after WorldBegin"],
    );
    assert_src_err("WorldBegin\nWorldBegin\n", 2, &["WorldBegin given twice"]);
    assert_src_err("Camera \"perspective\"\n", 2, &["no WorldBegin"]);
}

#[test]
fn error_parameter_types_and_values() {
    assert_src_err(
        "Camera \"perspective\"\n    \"integer fov\" 30\nWorldBegin\n",
        2,
        &["\"integer fov\"", "expected float"],
    );
    assert_src_err(
        "WorldBegin\nMaterial \"diffuse\"\n  \"rgb reflectance\" [ 0.5 0.5 ]\n",
        3,
        &["\"rgb reflectance\"", "expected 3 numbers, got 2"],
    );
    assert_src_err(
        "WorldBegin\nMaterial \"diffuse\" \"texture reflectance\" \"t\"\n",
        2,
        &["\"texture reflectance\"", "unknown spectrum texture \"t\""],
    );
    assert_src_err(
        "WorldBegin\nLightSource \"point\"\n \"blackbody I\" 0\n",
        3,
        &["blackbody", "temperature"],
    );
    assert_src_err(
        "WorldBegin\nMaterial \"diffuse\" \"rgb reflectance\" [ 1.5 0 0 ]\n",
        2,
        &["[0, 1]"],
    );
    assert_src_err(
        "Film \"rgb\"\n \"integer xresolution\" [ 1.5 ]\nWorldBegin\n",
        2,
        &["expected an integer, found number 1.5"],
    );
    assert_src_err(
        "Film \"rgb\" \"integer xresolution\" [ 0 ]\nWorldBegin\n",
        1,
        &["must be positive"],
    );
    assert_src_err(
        "WorldBegin\nMaterial \"diffuse\" \"colour reflectance\" [ 1 1 1 ]\n",
        2,
        &["unknown parameter type \"colour\""],
    );
    assert_src_err(
        "WorldBegin\nMaterial \"diffuse\" \"reflectance\" [ 1 1 1 ]\n",
        2,
        &["\"type name\""],
    );
    assert_src_err(
        "WorldBegin\nLightSource \"point\" \"float scale\" 1\n\"float scale\" 2\n",
        3,
        &["given twice"],
    );
    assert_src_err(
        "WorldBegin\nLightSource \"point\" \"bool x\" maybe\n",
        2,
        &["true or false"],
    );
    assert_src_err(
        "WorldBegin\nLightSource \"point\" \"float scale\" [ 1 [ 2 ] ]\n",
        2,
        &["\"[\" inside"],
    );
    assert_src_err(
        "WorldBegin\nLightSource \"point\"\n \"float scale\" [ 1 2\n",
        4,
        &["unexpected end of file"],
    );
    assert_src_err(
        "WorldBegin\nTranslate 1 2\n",
        3,
        &["unexpected end of file", "number"],
    );
    assert_src_err("WorldBegin\nTranslate 1 x 2\n", 2, &["expected a number"]);
    assert_src_err(
        "WorldBegin\nTransform [ 1 0 0 ]\n",
        2,
        &["expected a number, found \"]\""],
    );
    assert_src_err("WorldBegin\nRotate 10 0 0 0\n", 2, &["zero axis"]);
    assert_src_err("LookAt 0 0 0 0 0 1 0 0 1\nWorldBegin\n", 1, &["up vector"]);
    assert_src_err(
        "WorldBegin\nLightSource \"distant\" \"float illuminance\" 3\n",
        2,
        &["\"illuminance\""],
    );
    assert_src_err(
        "Camera \"perspective\"\n \"float lensradius\" -0.1\nWorldBegin\n",
        2,
        &["\"float lensradius\"", "must lie in [0, "],
    );
    assert_src_err(
        "WorldBegin\nMaterial \"dielectric\"\n \"float roughness\" -0.1\n",
        3,
        &["roughness must be finite and not negative"],
    );
    assert_src_err(
        "WorldBegin\nMaterial \"dielectric\"\n \"spectrum eta\" \"glass-XYZ\"\n",
        3,
        &["glass-XYZ"],
    );
    assert_src_err(
        "WorldBegin\nMaterial \"conductor\"\n \"spectrum eta\" \"metal-Pt-eta\"\n",
        3,
        &["metal-Pt-eta"],
    );
    assert_src_err(
        "WorldBegin\nMaterial \"conductor\" \"rgb reflectance\" [1 1 1]\n \"rgb k\" [1 1 1]\n",
        3,
        &["not both"],
    );
    assert_src_err(
        "WorldBegin\nMakeNamedMaterial \"x\" \"rgb reflectance\" [1 1 1]\n",
        2,
        &["\"string type\""],
    );
    assert_src_err("WorldBegin\nMakeNamedMaterial \"x\" \"string type\" \"diffuse\"\nMakeNamedMaterial \"x\" \"string type\" \"diffuse\"\n", 3, &["redefined"]);
    assert_src_err(
        "WorldBegin\nCoordSysTransform \"nowhere\"\n",
        2,
        &["unknown coordinate system \"nowhere\""],
    );
}

#[test]
fn error_unused_parameters() {
    assert_src_err(
        "WorldBegin\nLightSource \"point\"\n  \"rgb I\" [ 1 1 1 ]\n  \"float foo\" 1\n",
        4,
        &["unused parameter \"float foo\""],
    );
    assert_src_err(
        "Camera \"perspective\" \"float aperturediameter\" [ 1 ]\nWorldBegin\n",
        1,
        &["unused parameter \"float aperturediameter\""],
    );
    // pbrt-v3's Film "scale" is not a pbrt-v4 parameter (pbrt-v4 reports it unused too).
    assert_src_err(
        "Film \"rgb\"\n\"float scale\" 2\nWorldBegin\n",
        2,
        &["unused parameter \"float scale\""],
    );
    assert_src_err(
        "Sampler \"stratified\" \"integer pixelsamples\" 4\nWorldBegin\n",
        1,
        &["unused parameter \"integer pixelsamples\""],
    );
    assert_src_err(
        "PixelFilter \"box\" \"float sigma\" 1\nWorldBegin\n",
        1,
        &["unused parameter \"float sigma\""],
    );
    assert_src_err(
        "WorldBegin\nMaterial \"diffuse\" \"texture normalmap\" \"n\"\n",
        2,
        &["\"texture normalmap\": a texture is not supported for this parameter"],
    );
    assert_src_err("WorldBegin\nMaterial \"conductor\" \"float uroughness\" 0.1 \"float vroughness\" 0.1\n \"float roughness\" 0.2\n", 3, &["unused parameter \"float roughness\""]);
    // (`alpha` is read since shapes take it; a sphere's `radius` is not a mesh's.)
    assert_src_err(
        &format!("WorldBegin\n{TRI}\n  \"float radius\" 0.5\n"),
        3,
        &["unused parameter \"float radius\""],
    );
    assert_src_err(
        "WorldBegin\nShape \"sphere\" \"float radius\" 1\n \"float zmax\" 0.5\n",
        3,
        &["partial spheres"],
    );
    assert_src_err(
        "WorldBegin\nAreaLightSource \"diffuse\" \"string filename\" \"x.exr\"\n",
        2,
        &["unused parameter \"string filename\""],
    );
    assert_src_err("WorldBegin\nShape \"plymesh\" \"string filename\" \"x.ply\"\n\"texture displacement\" \"d\"\n", 3, &["\"texture displacement\": a texture is not supported for this parameter"]);
}

#[test]
fn error_named_material_and_blocks() {
    assert_src_err(
        "WorldBegin\nMakeNamedMaterial \"a\" \"string type\" \"diffuse\"\n\nNamedMaterial \"b\"\n",
        4,
        &["unknown named material \"b\""],
    );
    assert_src_err(
        "WorldBegin\nAttributeBegin\nAttributeEnd\nAttributeEnd\n",
        4,
        &["AttributeEnd without AttributeBegin"],
    );
    assert_src_err(
        "TransformEnd\nWorldBegin\n",
        1,
        &["TransformEnd without TransformBegin"],
    );
    assert_src_err(
        "WorldBegin\nAttributeBegin\nTransformBegin\nAttributeEnd\n",
        4,
        &["does not match the block opened at line 3"],
    );
    assert_src_err(
        "WorldBegin\nShape \"sphere\"\nAttributeBegin\n",
        3,
        &["AttributeBegin without a matching AttributeEnd"],
    );
}

#[test]
fn error_unterminated_string() {
    let r = load_src("WorldBegin\nMaterial \"diffuse\"\n  Shape \"trianglemesh\n");
    assert_err(r, "scene.pbrt", 3, &["unterminated string"]);
    let e = load_src("WorldBegin\nNamedMaterial \"abc").unwrap_err();
    assert_eq!(
        (e.loc.as_ref().unwrap().line, e.loc.as_ref().unwrap().col),
        (2, 15)
    );
    assert!(e.msg.contains("unterminated string"));
}

#[test]
fn media_textures_and_curves_are_clear_errors() {
    assert_src_err(
        "WorldBegin\n\nMakeNamedMedium \"fog\" \"string type\" \"nanovdb\" \"string filename\" \"a.nvdb\"\n",
        3,
        &["\"nanovdb\" is not supported yet"],
    );
    // A medium that only absorbs loads; its name must be defined before a shape uses it.
    assert_src_err(
        "WorldBegin\nMediumInterface \"\" \"fog\"\nShape \"sphere\"\n",
        2,
        &["undefined medium \"fog\""],
    );
    assert_src_err(
        "WorldBegin\nShape \"curve\" \"point3 P\" [0 0 0 1 0 0 2 0 0 3 0 0]\n",
        2,
        &["curves and hair are not supported"],
    );
}
