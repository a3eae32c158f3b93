//! Direct lighting against analytic irradiance: a Lambertian floor of reflectance rho lit by a
//! point, spot or distant light (E = I cos(theta) / r^2, E = L cos(theta)) and by a small
//! square area light (the exact form factor of a parallel rectangle). Radiance L = rho / pi E.
use crate::support as common;
use photon::accel::BackendKind;
use photon::light::Receiver;
use photon::math::{Vec2, Vec3};
use photon::scene::Scene;
use std::f32::consts::PI;
use std::path::PathBuf;

const RHO: [f32; 3] = [0.5, 0.6, 0.7];

fn write_scene(name: &str, camera_y: f32, res: u32, spp: u32, lights: &str) -> PathBuf {
    let text = format!(
        r#"LookAt 0 {camera_y} 0  0 0 0  0 0 1
Camera "perspective" "float fov" [ 70 ]
Film "rgb" "integer xresolution" [ {res} ] "integer yresolution" [ {res} ]
PixelFilter "box" "float xradius" [ 0.0001 ] "float yradius" [ 0.0001 ]
Sampler "stratified" "integer xsamples" [ {spp} ] "integer ysamples" [ 1 ] "bool jitter" true
Integrator "path" "integer maxdepth" [ 1 ]
WorldBegin
Material "diffuse" "rgb reflectance" [ {} {} {} ]
Shape "trianglemesh" "point3 P" [ -5 0 -5  5 0 -5  5 0 5  -5 0 5 ] "integer indices" [ 0 1 2 0 2 3 ]
{lights}
"#,
        RHO[0], RHO[1], RHO[2]
    );
    common::write_scene("direct_light", name, &text)
}

/// Renders `path` and returns, per pixel, (rendered, floor point seen through the centre).
fn render(path: &std::path::Path, backend: BackendKind) -> (Scene, Vec<(Vec3, Vec3)>) {
    common::render_floor(path, backend)
}

fn rho() -> Vec3 {
    Vec3::from_array(RHO)
}

/// Worst relative error over pixels with expected radiance above `floor`.
fn worst(px: &[(Vec3, Vec3)], expected: impl Fn(Vec3) -> Vec3, floor: f32) -> (f32, usize) {
    let mut worst = 0.0f32;
    let mut n = 0;
    for &(got, p) in px {
        let want = expected(p);
        if want.min_element() <= floor {
            continue;
        }
        n += 1;
        worst = worst.max(((got - want) / want).abs().max_element());
    }
    (worst, n)
}

#[test]
fn point_light_irradiance() {
    let (pos, i) = (Vec3::new(0.4, 1.2, -0.3), Vec3::new(2.0, 3.0, 4.0));
    let path = write_scene(
        "point",
        3.0,
        48,
        1,
        "LightSource \"point\" \"rgb I\" [ 2 3 4 ] \"point3 from\" [ 0.4 1.2 -0.3 ]",
    );
    for backend in [BackendKind::Embree, BackendKind::Obvhs] {
        let (_, px) = render(&path, backend);
        let (err, n) = worst(
            &px,
            |p| {
                let d = pos - p;
                rho() / PI * i * (d.y / d.length()) / d.length_squared()
            },
            1e-6,
        );
        println!("point light ({backend}): worst relative error {err:.2e} over {n} pixels");
        assert!(n > 2000 && err < 0.01, "{backend}: {err}");
    }
}

#[test]
fn spot_and_distant_light_irradiance() {
    // Spot pointing straight down from height 2: full intensity inside 20 degrees, none past 30.
    let spot = "LightSource \"spot\" \"rgb I\" [ 5 5 5 ] \"point3 from\" [ 0 2 0 ] \"point3 to\" [ 0 0 0 ] \"float coneangle\" [ 30 ] \"float conedeltaangle\" [ 10 ]";
    let (_, px) = render(&write_scene("spot", 3.0, 48, 1, spot), BackendKind::Embree);
    let (mut inside, mut outside) = (0, 0);
    for &(got, p) in &px {
        let d = Vec3::new(0.0, 2.0, 0.0) - p;
        let angle = (d.y / d.length()).acos().to_degrees();
        if angle < 19.5 {
            let want = rho() / PI * 5.0 * (d.y / d.length()) / d.length_squared();
            assert!(
                ((got - want) / want).abs().max_element() < 0.01,
                "spot at {p}: {got} vs {want}"
            );
            inside += 1;
        } else if angle > 30.5 {
            assert_eq!(got, Vec3::ZERO, "spot outside the cone at {p}");
            outside += 1;
        }
    }
    println!("spot: {inside} pixels inside checked, {outside} outside dark");
    assert!(inside > 200 && outside > 200);

    // Distant light from direction (1, 2, 0): E = L cos(theta) everywhere.
    let distant = "LightSource \"distant\" \"rgb L\" [ 1 2 3 ] \"point3 from\" [ 1 2 0 ] \"point3 to\" [ 0 0 0 ]";
    let (_, px) = render(
        &write_scene("distant", 3.0, 32, 1, distant),
        BackendKind::Embree,
    );
    let cos = 2.0 / 5.0f32.sqrt();
    let (err, n) = worst(&px, |_| rho() / PI * Vec3::new(1.0, 2.0, 3.0) * cos, 0.0);
    println!("distant: worst relative error {err:.2e} over {n} pixels");
    assert!(n == 32 * 32 && err < 0.01);
}

/// bdpt and vcm under a distant light on a bare floor: a light sample finds every pixel's
/// direct light exactly (visibility and `E cos` are constant), so every pixel is exact at
/// 2 spp once light tracing leaves direct light to the light samples (with light tracing
/// weighed by the balance heuristic its splats made pixels up to 33% off).
#[test]
fn bidirectional_direct_light_under_a_distant_light_is_exact() {
    use photon::integrator::IntegratorKind;
    let distant = "LightSource \"distant\" \"rgb L\" [ 1 2 3 ] \"point3 from\" [ 1 2 0 ] \"point3 to\" [ 0 0 0 ]";
    let path = write_scene("distant-bidir", 3.0, 32, 2, distant);
    let want = rho() / PI * Vec3::new(1.0, 2.0, 3.0) * (2.0 / 5.0f32.sqrt());
    for kind in [IntegratorKind::Bdpt, IntegratorKind::Vcm] {
        let (_, px) = common::render_floor_with(&path, BackendKind::Embree, kind, |_| {});
        let (err, n) = worst(&px, |_| want, 0.0);
        println!("{kind:?}: worst relative error {err:.2e} over {n} pixels");
        assert!(n == 32 * 32 && err < 1e-3, "{kind:?}: {err}");
    }
    // Merging at every vertex competes with the light samples here; its weights must leave
    // light tracing out as theirs do (they did not: 8% dark at 2 px, 16 spp). Seeds 0-2:
    // 0.9955, 1.0009, 1.0000.
    let (_, px) = common::render_floor_with(&path, BackendKind::Embree, IntegratorKind::Vcm, |s| {
        s.spp = 16;
        s.vcm.all_merges = true;
        s.vcm.radius = photon::integrator::vcm::MergeRadius::Pixels(2.0);
    });
    let mean = px.iter().map(|p| p.0).sum::<Vec3>() / px.len() as f32;
    let off = ((mean - want) / want).abs().max_element();
    println!("vcm, all merges: mean {mean} against {want}: {off:.4} off");
    assert!(off < 0.03, "vcm with all merges: mean {mean} vs {want}");
}

/// Form factor from a point to a rectangle `[0, x] x [0, y]` in a parallel plane at unit
/// height, one corner straight above (odd in x and in y, so signed corners combine).
fn corner_factor(x: f32, y: f32) -> f32 {
    let (a, b) = ((1.0 + x * x).sqrt(), (1.0 + y * y).sqrt());
    (x / a * (y / a).atan() + y / b * (x / b).atan()) / (2.0 * PI)
}

/// The floor's radiance at `p` under the tests' 0.5 x 0.5 quad of radiance `l` at height 1,
/// centred over (0.2, -0.1) and facing down (its exact form factor).
fn quad_radiance(p: Vec3, l: f32) -> Vec3 {
    let (h, half, c) = (1.0f32, 0.25f32, Vec2::new(0.2, -0.1));
    let (x0, x1) = ((c.x - half - p.x) / h, (c.x + half - p.x) / h);
    let (z0, z1) = ((c.y - half - p.z) / h, (c.y + half - p.z) / h);
    let f = corner_factor(x1, z1) - corner_factor(x0, z1) - corner_factor(x1, z0)
        + corner_factor(x0, z0);
    rho() / PI * (PI * l * f)
}

/// The largest channel's relative error of the image's sum against `expected`'s.
fn mean_error(px: &[(Vec3, Vec3)], expected: impl Fn(Vec3) -> Vec3) -> f32 {
    let (mut sum_got, mut sum_want) = (Vec3::ZERO, Vec3::ZERO);
    for &(got, p) in px {
        sum_got += got;
        sum_want += expected(p);
    }
    ((sum_got - sum_want) / sum_want).abs().max_element()
}

#[test]
fn quad_light_irradiance() {
    // A 0.5 x 0.5 light at height 1, centred at (0.2, 1, -0.1), facing down; the camera sits
    // under it at height 0.5 looking at the floor.
    let l = 5.0;
    let light = "AttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [ 5 5 5 ]\nShape \"trianglemesh\" \"point3 P\" [ -0.05 1 -0.35  0.45 1 -0.35  0.45 1 0.15  -0.05 1 0.15 ] \"integer indices\" [ 0 1 2 0 2 3 ]\nAttributeEnd";
    let (_, px) = render(
        &write_scene("quad", 0.5, 24, 256, light),
        BackendKind::Embree,
    );
    let expected = |p: Vec3| quad_radiance(p, l);
    let mean_err = mean_error(&px, expected);
    let (err, n) = worst(&px, expected, 0.0);
    println!(
        "quad light: mean relative error {mean_err:.2e}, worst pixel {err:.2e} over {n} pixels"
    );
    assert!(mean_err < 0.01, "mean {mean_err}");
    assert!(err < 0.05, "worst pixel {err}");
}

/// The same quad beside two lights that cannot reach the floor, each 20-30 times its power:
/// a larger quad above it facing up and a spot pointing up. Shadow rays are picked by what each
/// light can send to the receiving point (`light::select`, pbrt-v4's light bounds), so the
/// floor gets the quad's exact irradiance at the same sample count and error as the quad
/// alone (worst pixel 0.004); picked by power, 30 of 31 shadow rays went to the decoys
/// (worst pixel 0.35 at 256 spp).
#[test]
fn lights_facing_away_take_no_shadow_rays() {
    let lights = "AttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [ 5 5 5 ]\nShape \"trianglemesh\" \"point3 P\" [ -0.05 1 -0.35  0.45 1 -0.35  0.45 1 0.15  -0.05 1 0.15 ] \"integer indices\" [ 0 1 2 0 2 3 ]\nAttributeEnd
AttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [ 25 25 25 ]\nShape \"trianglemesh\" \"point3 P\" [ -0.5 2 0.5  0.5 2 0.5  0.5 2 -0.5  -0.5 2 -0.5 ] \"integer indices\" [ 0 1 2 0 2 3 ]\nAttributeEnd
LightSource \"spot\" \"rgb I\" [ 200 200 200 ] \"point3 from\" [ 0 0.8 0 ] \"point3 to\" [ 0 2 0 ] \"float coneangle\" [ 30 ] \"float conedeltaangle\" [ 10 ]";
    let file = write_scene("facing-away", 0.5, 24, 256, lights);
    let (scene, px) = render(&file, BackendKind::Embree);
    let lights = scene.emitters();
    let powers = lights.powers();
    assert!(
        powers[1] > 19.0 * powers[0] && powers[2] > 19.0 * powers[0],
        "{powers:?}"
    );
    // Picks follow pmf_at (what MIS weighs emitter hits by), which sums to 1; on the floor
    // only the quad is picked.
    for p in [
        Vec3::new(0.1, 0.0, 0.2),
        Vec3::new(0.0, 1.5, 0.0),
        Vec3::new(2.0, 2.5, 1.0),
    ] {
        let r = Receiver::new(p, Vec3::Y);
        let n = 100_000;
        let mut counts = [0usize; 3];
        for k in 0..n {
            let (i, pmf) = lights.pick_at(r, (k as f32 + 0.5) / n as f32).unwrap();
            assert!((pmf - lights.pmf_at(r, i)).abs() < 1e-6);
            counts[i] += 1;
        }
        let pmfs: Vec<f32> = (0..3).map(|i| lights.pmf_at(r, i)).collect();
        println!("at {p}: picks {counts:?}, pmf {pmfs:?}");
        assert!((pmfs.iter().sum::<f32>() - 1.0).abs() < 1e-5);
        for i in 0..3 {
            assert!((counts[i] as f32 / n as f32 - pmfs[i]).abs() < 1e-3);
        }
        if p.y == 0.0 {
            assert_eq!(counts[0], n, "at {p}: {counts:?}");
        }
    }
    let expected = |p: Vec3| quad_radiance(p, 5.0);
    let mean_err = mean_error(&px, expected);
    let (err, n) = worst(&px, expected, 0.0);
    println!("quad beside lights facing away: mean relative error {mean_err:.2e}, worst pixel {err:.2e} over {n} pixels");
    assert!(mean_err < 0.01, "mean {mean_err}");
    assert!(err < 0.05, "worst pixel {err}");
    // bdpt's and vcm's light samples pick by the same importance (their light subpaths by
    // power): on this diffuse floor their direct light is light samples and emission hits
    // alone, as exact as the path tracer's.
    use photon::integrator::IntegratorKind;
    for kind in [IntegratorKind::Bdpt, IntegratorKind::Vcm] {
        let (_, px) = common::render_floor_with(&file, BackendKind::Embree, kind, |_| {});
        let mean_err = mean_error(&px, expected);
        let (err, n) = worst(&px, expected, 0.0);
        println!(
            "{kind:?}: mean relative error {mean_err:.2e}, worst pixel {err:.2e} over {n} pixels"
        );
        assert!(mean_err < 0.01, "{kind:?}: mean {mean_err}");
        assert!(err < 0.05, "{kind:?}: worst pixel {err}");
    }
}

/// The chromaticity (x, y) of a linear sRGB value, by the IEC 61966-2-1 sRGB-to-XYZ matrix.
fn chromaticity(c: Vec3) -> (f32, f32) {
    let x = 0.4124 * c.x + 0.3576 * c.y + 0.1805 * c.z;
    let y = 0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z;
    let z = 0.0193 * c.x + 0.1192 * c.y + 0.9505 * c.z;
    (x / (x + y + z), y / (x + y + z))
}

/// A blackbody distant light straight down, `"blackbody L" [ 2856 ] "float scale" 3`: in
/// pbrt-v4 its luminance is `scale` (the spectrum is divided by its photometric integral), and
/// 2856 K is CIE illuminant A, chromaticity (0.44757, 0.40745). The floor's radiance is
/// rho / pi * L per channel, so L recovered from the image must have luminance 3 and A's
/// chromaticity.
#[test]
fn blackbody_light_renders_with_its_luminance() {
    let distant = "LightSource \"distant\" \"blackbody L\" [ 2856 ] \"float scale\" 3 \"point3 from\" [ 0 1 0 ] \"point3 to\" [ 0 0 0 ]";
    let (_, px) = render(
        &write_scene("blackbody", 3.0, 16, 1, distant),
        BackendKind::Embree,
    );
    for &(got, p) in &px {
        let l = got * PI / rho();
        let lum = photon::math::luminance(l);
        let (x, y) = chromaticity(l);
        assert!(
            (lum - 3.0).abs() < 3e-3 * 3.0,
            "at {p}: L {l}, luminance {lum}"
        );
        assert!(
            (x - 0.44757).abs() < 1e-3 && (y - 0.40745).abs() < 1e-3,
            "at {p}: ({x}, {y})"
        );
    }
}

/// An infinite light `L` with a portal lights the floor exactly as a one-sided area light of
/// radiance `L` filling the portal would (pbrt-v4's `PortalImageInfiniteLight::Le` is zero
/// for rays that do not leave through the portal): the same analytic form factor as
/// [`quad_light_irradiance`], here for the whole image's mean. With the corners in the
/// opposite order the portal faces down (its outside is the floor side) and no light comes
/// through.
#[test]
fn portal_light_lights_only_through_the_portal() {
    let corners = "-0.05 1 -0.35  0.45 1 -0.35  0.45 1 0.15  -0.05 1 0.15";
    let light =
        format!("LightSource \"infinite\" \"rgb L\" [ 5 5 5 ] \"point3 portal\" [ {corners} ]");
    let (_, px) = render(
        &write_scene("portal", 0.5, 16, 1024, &light),
        BackendKind::Embree,
    );
    let expected = |p: Vec3| quad_radiance(p, 5.0);
    let mean_err = mean_error(&px, expected);
    println!("portal light: relative error of the mean {mean_err:.2e}");
    assert!(mean_err < 0.02, "mean {mean_err}");

    let reversed = "-0.05 1 0.15  0.45 1 0.15  0.45 1 -0.35  -0.05 1 -0.35";
    let light =
        format!("LightSource \"infinite\" \"rgb L\" [ 5 5 5 ] \"point3 portal\" [ {reversed} ]");
    let (_, px) = render(
        &write_scene("portal-down", 0.5, 8, 16, &light),
        BackendKind::Embree,
    );
    assert!(px.iter().all(|(got, _)| *got == Vec3::ZERO));
}
