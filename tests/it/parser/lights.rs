//! `LightSource` and `AreaLightSource`: point, spot, distant, area, infinite and portal lights,
//! blackbody emission, emitters with alpha.

use super::*;
use photon::math::luminance;

#[test]
fn point_spot_distant_lights() {
    let s = ok(r#"WorldBegin
Translate 1 0 0
LightSource "point" "point3 from" [ 1 2 3 ] "rgb I" [ 1 2 3 ] "float scale" 2
LightSource "point" "float power" 100
Identity
Rotate 90 0 0 1
LightSource "spot" "point3 from" [ 0 5 0 ] "point3 to" [ 0 0 0 ] "float coneangle" 30 "float conedeltaangle" 10
LightSource "spot" "float power" 10
Identity
LightSource "distant" "point3 from" [ 0 10 0 ] "point3 to" [ 0 0 0 ] "rgb L" [ 1 1 1 ] "float scale" 2
"#);
    assert_eq!(
        s.lights[0],
        Light::Point(photon::light::PointLight {
            pos: Vec3::new(2.0, 2.0, 3.0),
            intensity: Vec3::new(2.0, 4.0, 6.0)
        })
    );
    let Light::Point(photon::light::PointLight { pos, intensity }) = s.lights[1] else {
        panic!()
    };
    assert_eq!(pos, Vec3::X);
    assert_vec(intensity, Vec3::splat(100.0 / (4.0 * PI)), 1e-5);
    // R_z(90) maps (x, y) to (-y, x).
    let Light::Spot(photon::light::SpotLight {
        pos,
        dir,
        intensity,
        cos_falloff_start,
        cos_falloff_end,
    }) = s.lights[2]
    else {
        panic!()
    };
    assert_vec(pos, Vec3::new(-5.0, 0.0, 0.0), 1e-6);
    assert_vec(dir, Vec3::X, 1e-6);
    assert_eq!(intensity, Vec3::ONE);
    assert!(close(cos_falloff_end, 0.866_025_4, 1e-6));
    assert!(close(cos_falloff_start, 0.939_692_6, 1e-6));
    // Defaults 30 / 5 degrees; power 10 over pbrt-v4's k_e = 2 pi (1 - (cs + ce) / 2).
    let Light::Spot(photon::light::SpotLight {
        dir,
        intensity,
        cos_falloff_start,
        cos_falloff_end,
        ..
    }) = s.lights[3]
    else {
        panic!()
    };
    assert_vec(dir, Vec3::Z, 1e-6); // (0,0,1) is not moved by R_z
    let (cs, ce) = (25f32.to_radians().cos(), 30f32.to_radians().cos());
    assert!(close(cos_falloff_start, cs, 1e-6) && close(cos_falloff_end, ce, 1e-6));
    let k = 10.0 / (2.0 * PI * (1.0 - 0.5 * (cs + ce)));
    assert_vec(intensity, Vec3::splat(k), 1e-3);
    assert_eq!(
        s.lights[4],
        Light::Distant(photon::light::DistantLight {
            dir: -Vec3::Y,
            l: Vec3::splat(2.0)
        })
    );
}

#[test]
fn area_lights() {
    let quad = r#"Shape "trianglemesh" "point3 P" [ 0 0 0 2 0 0 2 1 0 0 1 0 ] "integer indices" [ 0 1 2 0 2 3 ]"#;
    let s = ok(&format!(
        r#"WorldBegin
AttributeBegin
AreaLightSource "diffuse" "rgb L" [ 1 2 3 ] "float scale" 3 "bool twosided" true
{quad}
{quad}
AttributeEnd
{quad}
AttributeBegin
AreaLightSource "diffuse" "float power" 10 "bool twosided" true
{quad}
AttributeEnd
AttributeBegin
AreaLightSource "diffuse" "float power" 10
Scale 2 2 2
Shape "sphere" "float radius" 0.5
AttributeEnd
"#
    ));
    assert_eq!(s.lights.len(), 4);
    assert_eq!(s.meshes.len(), 5);
    for (i, light) in s.lights.iter().enumerate() {
        let Light::Area { mesh, .. } = light else {
            panic!()
        };
        assert_eq!(s.meshes[*mesh as usize].area_light, Some(i as u32));
    }
    assert_eq!(
        s.lights[0],
        Light::Area {
            mesh: 0,
            l: Vec3::new(3.0, 6.0, 9.0),
            two_sided: true
        }
    );
    assert!(matches!(s.lights[1], Light::Area { mesh: 1, .. }));
    assert!(s.meshes[2].area_light.is_none());
    // power 10 over a two-sided 2 x 1 quad: L = 10 / (pi * 2 * 2).
    let Light::Area {
        mesh: 3,
        l,
        two_sided: true,
    } = s.lights[2]
    else {
        panic!()
    };
    assert_vec(l, Vec3::splat(10.0 / (4.0 * PI)), 1e-5);
    // power 10 over a one-sided sphere of world radius 1: L = 10 / (pi * 4 pi).
    let Light::Area {
        mesh: 4,
        l,
        two_sided: false,
    } = s.lights[3]
    else {
        panic!()
    };
    assert_vec(l, Vec3::splat(10.0 / (4.0 * PI * PI)), 1e-5);
}

/// Blackbody `L`/`I` on every light type: luminance `scale` (pbrt-v4 divides by the spectrum's
/// photometric integral), then `power`/`illuminance` as for RGB; the colour of 2856 K is CIE
/// illuminant A.
#[test]
fn blackbody_lights() {
    let s = ok(r#"WorldBegin
LightSource "point" "blackbody I" [ 2856 ] "float scale" 2
LightSource "point" "blackbody I" 6504 "float power" 100
LightSource "spot" "blackbody I" [ 3000 ]
LightSource "distant" "blackbody L" [ 5000 ] "float scale" 0.5
LightSource "infinite" "blackbody L" [ 8000 ] "float illuminance" 3.14159265
AttributeBegin
AreaLightSource "diffuse" "blackbody L" [ 4000 ] "float scale" 7
Shape "trianglemesh" "point3 P" [ 0 0 0 1 0 0 0 1 0 ] "integer indices" [ 0 1 2 ]
AttributeEnd
"#);
    let Light::Point(photon::light::PointLight { intensity, .. }) = s.lights[0] else {
        panic!()
    };
    assert!(close(luminance(intensity), 2.0, 1e-3), "{intensity}");
    let xyz = Vec3::new(
        0.4124 * intensity.x + 0.3576 * intensity.y + 0.1805 * intensity.z,
        luminance(intensity),
        0.0193 * intensity.x + 0.1192 * intensity.y + 0.9505 * intensity.z,
    );
    let (x, y) = (xyz.x / xyz.element_sum(), xyz.y / xyz.element_sum());
    assert!(
        (x - 0.44757).abs() < 1e-3 && (y - 0.40745).abs() < 1e-3,
        "({x}, {y})"
    );
    let Light::Point(photon::light::PointLight { intensity, .. }) = s.lights[1] else {
        panic!()
    };
    assert!(close(luminance(intensity), 100.0 / (4.0 * PI), 1e-3));
    assert!(
        (intensity / luminance(intensity) - Vec3::ONE)
            .abs()
            .max_element()
            < 0.05
    );
    let Light::Spot(photon::light::SpotLight { intensity, .. }) = s.lights[2] else {
        panic!()
    };
    assert!(close(luminance(intensity), 1.0, 1e-3) && intensity.x > 1.5 * intensity.z);
    let Light::Distant(photon::light::DistantLight { l, .. }) = s.lights[3] else {
        panic!()
    };
    assert!(close(luminance(l), 0.5, 1e-3));
    let Light::Infinite { map } = &s.lights[4] else {
        panic!()
    };
    assert!(close(luminance(map.le(Vec3::Y)), 1.0, 1e-3)); // illuminance pi: L = 1
    let Light::Area { l, .. } = s.lights[5] else {
        panic!()
    };
    assert!(close(luminance(l), 7.0, 1e-3));

    assert_src_err(
        "WorldBegin\nLightSource \"point\"\n \"blackbody I\" [ -5 ]\n",
        3,
        &["\"blackbody I\"", "temperature must be finite and > 0"],
    );
    assert_src_err(
        "WorldBegin\nLightSource \"point\"\n \"blackbody I\" [ 3000 1 ]\n",
        3,
        &["\"blackbody I\""],
    );
    assert_src_err(
        "WorldBegin\nMaterial \"diffuse\" \"blackbody reflectance\" 3000\n",
        2,
        &["only supported for light emission"],
    );
}

/// A sphere whose `Shape` fails after it was read (alpha on an emitter, as kroken's
/// `lights.pbrt` has) is skipped in collect mode without a panic at the end (the sphere was
/// queued for tessellation without its mesh before).
#[test]
fn failed_emitting_sphere_is_skipped_in_collect_mode() {
    let dir = TempDir::new("photon-parser");
    let path = dir.write(
        "scene.pbrt",
        "WorldBegin\nAttributeBegin\nAreaLightSource \"diffuse\" \"blackbody L\" 6500\nShape \"sphere\" \"float radius\" 90 \"float alpha\" 0.5\nAttributeEnd\nShape \"sphere\"\n",
    );
    let got = photon::scene::loader::load_collecting(&path);
    let msgs: Vec<String> = got.errors.iter().map(|e| e.to_string()).collect();
    assert_eq!(msgs.len(), 1, "{msgs:?}");
    assert!(msgs[0].contains(":4:") && msgs[0].contains("alpha other than 0 on an emitting shape"));
    assert_eq!(got.scene.meshes.len(), 1);
    assert!(!got.scene.meshes[0].indices.is_empty());
}

/// pbrt-v4's area light emits nothing where its shape's alpha masks it, and rays pass there:
/// an emitting sphere of constant alpha 0 (kroken's sun) is left out, with a note, and the
/// scene keeps its other shapes and lights.
#[test]
fn emitting_shape_with_alpha_zero_is_left_out() {
    let dir = TempDir::new("photon-parser");
    let path = dir.write(
        "scene.pbrt",
        "WorldBegin\nLightSource \"point\" \"rgb I\" [ 1 1 1 ]\nAttributeBegin\nAreaLightSource \"diffuse\" \"blackbody L\" 6500\nShape \"sphere\" \"float radius\" 90 \"float alpha\" 0\nAttributeEnd\nShape \"sphere\"\n",
    );
    let got = photon::scene::loader::load_collecting(&path);
    assert!(got.errors.is_empty(), "{:?}", got.errors);
    let scene = got.scene;
    assert_eq!(scene.meshes.len(), 1, "only the plain sphere");
    assert!(scene.meshes[0].area_light.is_none());
    assert_eq!(scene.lights.len(), 1, "only the point light");
    assert!(
        scene
            .notes
            .iter()
            .any(|n| n.contains(":5:") && n.contains("alpha 0")),
        "{:?}",
        scene.notes
    );
}

/// pbrt-v4's spot light reads `conedeltaangle` (lights.cpp, `SpotLight::Create`), so a
/// `conedelta` is an unused parameter there and here.
#[test]
fn spot_conedelta_is_conedeltaangle() {
    assert_src_err(
        "WorldBegin\nLightSource \"spot\"\n \"float conedelta\" 5\n",
        3,
        &["unused parameter \"float conedelta\""],
    );
}

/// kroken's sky: `"blackbody L" 6500 "float scale" 7.5` with a portal. pbrt-v4's portal light
/// converts `L` with `SpectrumToXYZ` and no one-nit normalisation, so its luminance is that of
/// the peak-normalised Planck spectrum, 0.88589 at 6500 K (pbrt-v4's 1 nm CIE table summed in
/// Python), times 7.5; without the portal it is 7.5.
#[test]
fn portal_blackbody_is_not_normalised() {
    let lum = |portal: &str| {
        let s = ok(&format!(
            "WorldBegin\nLightSource \"infinite\" {portal} \"blackbody L\" 6500 \"float scale\" 7.5\n"
        ));
        let Light::Infinite { map } = &s.lights[0] else {
            panic!()
        };
        luminance(map.le(Vec3::Y))
    };
    let with = lum("\"point3 portal\" [ 0 0 0  0 1 0  1 1 0  1 0 0 ]");
    assert!(close(with, 7.5 * 0.885_888_6, 2e-3), "{with}");
    assert!(close(lum(""), 7.5, 1e-3));
}
