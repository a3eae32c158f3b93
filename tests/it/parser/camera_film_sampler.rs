//! Scene-wide options: the defaults, `Camera` (lens, screen window, shutter), `Film` (sensor,
//! crop, gbuffer), `Sampler` and `PixelFilter`.

use super::*;

#[test]
fn options_and_defaults() {
    let s = ok("WorldBegin\n");
    assert_eq!(s.integrator.name, "default");
    assert!(s.integrator.params.is_empty() && s.integrator.loc.is_none());
    assert_eq!(
        (s.film.xres, s.film.yres, s.film.filename.clone()),
        (1280, 720, None)
    );
    assert_eq!(
        s.filter,
        FilterDesc::Gaussian {
            radius: Vec2::splat(1.5),
            sigma: 0.5
        }
    );
    assert_eq!(s.camera.fov_deg, 90.0);
    assert_eq!(s.camera.world_from_camera, Mat4::IDENTITY);
    assert_eq!(s.sampler.pixel_samples, 16);
    assert!(s.meshes.is_empty() && s.materials.is_empty() && s.lights.is_empty());

    let s = ok(
        r#"Sampler "stratified" "integer xsamples" 2 "integer ysamples" [ 3 ] "bool jitter" "false"
PixelFilter "gaussian" "float xradius" 2 "float sigma" 0.25
Film "rgb" "integer xresolution" 64 "string filename" "out.exr"
Camera "perspective" "float lensradius" 0
Integrator "photonmap" "integer photons" 1000 "float radius" 0.1
WorldBegin
"#,
    );
    assert_eq!(
        (s.sampler.name.as_str(), s.sampler.pixel_samples),
        ("stratified", 6)
    );
    assert_eq!(
        s.filter,
        FilterDesc::Gaussian {
            radius: Vec2::new(2.0, 1.5),
            sigma: 0.25
        }
    );
    assert_eq!((s.film.xres, s.film.yres), (64, 720));
    assert_eq!(s.film.filename.as_deref(), Some("out.exr"));
    assert_eq!(s.integrator.name, "photonmap");
    assert_eq!(s.integrator.loc.as_ref().unwrap().line, 5);
    let mut p = s.integrator.params.clone();
    assert_eq!(p.get_int("photons", 0).unwrap(), 1000);
    assert_eq!(p.get_float("radius", 0.0).unwrap(), 0.1);
    p.check_unused().unwrap();

    let s =
        ok("PixelFilter \"triangle\"\nSampler \"halton\" \"integer pixelsamples\" 7\nWorldBegin\n");
    assert_eq!(
        s.filter,
        FilterDesc::Triangle {
            radius: Vec2::splat(2.0)
        }
    );
    assert_eq!(
        (s.sampler.name.as_str(), s.sampler.pixel_samples),
        ("halton", 7)
    );
    let s = ok("PixelFilter \"box\" \"float yradius\" 1\nWorldBegin\n");
    assert_eq!(
        s.filter,
        FilterDesc::Box {
            radius: Vec2::new(0.5, 1.0)
        }
    );
}

#[test]
fn camera_lens_screen_window_and_shutter() {
    let s = ok(
        r#"Camera "perspective" "float fov" 30 "float lensradius" 0.25 "float focaldistance" 7
    "float screenwindow" [ -2 1 -0.5 1.5 ] "float shutteropen" 0.5 "float shutterclose" 2
WorldBegin
"#,
    );
    let c = &s.camera;
    assert_eq!((c.lens_radius, c.focal_distance), (0.25, 7.0));
    assert_eq!(c.screen_window, Some([-2.0, 1.0, -0.5, 1.5]));
    assert_eq!(c.exposure_time, 1.5);
    // pbrt-v4's defaults: a pinhole focused at 1e6, the image's own window, exposure 1.
    let s =
        ok("Camera \"perspective\" \"float focaldistance\" 3 \"float lensradius\" 0\nWorldBegin\n");
    assert_eq!((s.camera.lens_radius, s.camera.focal_distance), (0.0, 3.0));
    assert_eq!(
        (s.camera.screen_window, s.camera.exposure_time),
        (None, 1.0)
    );
    assert_eq!(ok("WorldBegin\n").camera.focal_distance, 1e6);
    // frameaspectratio: [-f, f] x [-1, 1] when wider than tall, else [-1, 1] x [-1/f, 1/f].
    let s = ok("Camera \"perspective\" \"float frameaspectratio\" 2\nWorldBegin\n");
    assert_eq!(s.camera.screen_window, Some([-2.0, 2.0, -1.0, 1.0]));
    let s = ok("Camera \"perspective\" \"float frameaspectratio\" 0.5\nWorldBegin\n");
    assert_eq!(s.camera.screen_window, Some([-1.0, 1.0, -2.0, 2.0]));
    for (params, needle) in [
        (
            "\"float focaldistance\" 0",
            "\"float focaldistance\": must be positive",
        ),
        (
            "\"float screenwindow\" [ -1 1 -1 ]",
            "expected four values xmin xmax ymin ymax",
        ),
        ("\"float screenwindow\" [ 1 -1 -1 1 ]", "min < max"),
        ("\"float frameaspectratio\" -1", "must be positive"),
        (
            "\"float shutteropen\" 1 \"float shutterclose\" 1",
            "must be after",
        ),
    ] {
        assert_src_err(
            &format!("Camera \"perspective\"\n {params}\nWorldBegin\n"),
            2,
            &[needle],
        );
    }
}

/// A Camera that fails to load still defines the "camera" coordinate system (pbrt-v4 defines it
/// in the directive's handler), so a later `CoordSysTransform "camera"` is not an error too.
#[test]
fn rejected_camera_still_defines_its_coordinate_system() {
    let dir = TempDir::new("photon-parser");
    let path = dir.write(
        "scene.pbrt",
        r#"Translate 0 0 -4
Camera "realistic" "string lensfile" "wide.dat"
WorldBegin
CoordSysTransform "camera"
LightSource "point" "point3 from" [ 0 0 0 ]
"#,
    );
    let got = photon::scene::loader::load_collecting(&path);
    let errs: Vec<String> = got.errors.iter().map(|e| e.to_string()).collect();
    assert_eq!(errs.len(), 1, "{errs:?}");
    assert!(errs[0].contains("scene.pbrt:2:8") && errs[0].contains("\"realistic\""));
    // Camera space is the inverse of the CTM: the eye is at world (0, 0, 4).
    let Light::Point(photon::light::PointLight { pos, .. }) = got.scene.lights[0] else {
        panic!()
    };
    assert_vec(pos, Vec3::new(0.0, 0.0, 4.0), 1e-6);
}

#[test]
fn film_sensor_crop_and_gbuffer() {
    let s = ok(
        r#"Film "rgb" "float iso" 250 "string sensor" "cie1931" "float whitebalance" 0
    "float maxcomponentvalue" 10 "float cropwindow" [ 0.9 0.1 1.5 -0.2 ]
Camera "perspective" "float shutterclose" 0.5
WorldBegin
"#,
    );
    assert_eq!((s.film.iso, s.film.max_component), (250.0, 10.0));
    // Ordered and clamped to [0, 1] per axis, as pbrt-v4 does.
    assert_eq!(
        s.film.crop,
        Some(photon::film::Crop::Window([0.1, 0.9, 0.0, 1.0]))
    );
    assert_eq!(s.film.imaging_ratio(s.camera.exposure_time), 1.25);
    assert_eq!(s.film.white_balance, 0.0);
    let s = ok("Film \"rgb\" \"float whitebalance\" 9000\nWorldBegin\n");
    assert_eq!(s.film.white_balance, 9000.0);
    let s = ok("Film \"rgb\"\nWorldBegin\n");
    assert_eq!(
        (s.film.iso, s.film.max_component, s.film.crop),
        (100.0, f32::INFINITY, None)
    );
    assert!(s.notes.is_empty());
    // gbuffer: an RGB film plus its data channels, in the space it names (camera by default).
    let s = ok("Film \"gbuffer\" \"string coordinatesystem\" \"world\" \"string filename\" \"a.exr\" \"integer xresolution\" 32\nWorldBegin\n");
    assert_eq!(s.film.xres, 32);
    assert!(s.notes.is_empty(), "{:?}", s.notes);
    assert_eq!(s.film.gbuffer, Some(photon::integrator::aov::Space::World));
    let s = ok("Film \"gbuffer\"\nWorldBegin\n");
    assert_eq!(s.film.gbuffer, Some(photon::integrator::aov::Space::Camera));
    assert_eq!(ok("Film \"rgb\"\nWorldBegin\n").film.gbuffer, None);
    for (film, needle) in [
        (
            "\"string sensor\" \"nikon_d850\"",
            "sensor \"nikon_d850\" is not supported",
        ),
        (
            "\"float whitebalance\" 3000",
            "must be 0 (none) or a daylight temperature in [3998, 100000] K",
        ),
        ("\"float iso\" 0", "\"float iso\": must be positive"),
        ("\"float maxcomponentvalue\" 0", "must be positive"),
        ("\"float cropwindow\" [ 0 1 0 ]", "four finite values"),
        (
            "\"float cropwindow\" [ 0.5 0.5 0 1 ]",
            "no pixel of the 1280x720 image",
        ),
    ] {
        assert_src_err(
            &format!("Film \"rgb\"\n {film}\nWorldBegin\n"),
            2,
            &[needle],
        );
    }
    assert_src_err(
        "Film \"gbuffer\"\n \"string coordinatesystem\" \"screen\"\nWorldBegin\n",
        2,
        &["unknown coordinate system \"screen\""],
    );
    assert_src_err(
        "Film \"gbuffer\"\n \"string filename\" \"a.png\"\nWorldBegin\n",
        2,
        &["EXR only"],
    );
}
