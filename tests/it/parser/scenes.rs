//! The three shared scenes against their files, the repository's scenes, and robustness:
//! cut and mangled input, a multi-megabyte file, the loader's memory budget.

use super::*;

#[test]
fn cornell_box_loads() {
    let path = shared("cornell-box/scene-v4.pbrt");
    let text = std::fs::read_to_string(&path).unwrap();
    let s = load(&path).unwrap_or_else(|e| panic!("{e}"));

    let tris: usize = lists_after(&text, "\"integer indices\"")
        .iter()
        .map(|l| l.len() / 3)
        .sum();
    assert_eq!(s.triangle_count(), tris);
    assert_eq!(s.meshes.len(), text.matches("Shape ").count());
    assert_eq!(s.materials.len(), text.matches("MakeNamedMaterial").count());
    assert_eq!(s.materials.len(), 8);
    assert_eq!(s.lights.len(), 1);
    let Light::Area { mesh, l, two_sided } = &s.lights[0] else {
        panic!("not an area light: {:?}", s.lights[0]);
    };
    assert_eq!(*l, Vec3::new(17.0, 12.0, 4.0));
    assert!(!two_sided);
    assert_eq!(s.meshes[*mesh as usize].area_light, Some(0));
    assert_eq!(
        s.materials[s.meshes[*mesh as usize].material as usize],
        diffuse(Vec3::ZERO)
    );
    // The light is the last shape: 0.47 x 0.38 at y = 1.98.
    let lm = &s.meshes[*mesh as usize];
    let area: f32 = (0..2).map(|t| lm.area(t)).sum();
    assert!(close(area, 0.47 * 0.38, 1e-5));
    // Floor material: LeftWall colour appears on the left wall.
    let red = diffuse(Vec3::new(0.63, 0.065, 0.05));
    assert_eq!(s.materials.iter().filter(|m| **m == red).count(), 1);

    let cam = s.camera.world_from_camera;
    assert_vec(
        cam.transform_point3(Vec3::ZERO),
        Vec3::new(0.0, 1.0, 6.8),
        1e-5,
    );
    assert_vec(
        cam.transform_vector3(Vec3::Z),
        Vec3::new(0.0, 0.0, -1.0),
        1e-6,
    );
    assert_eq!(s.camera.fov_deg, 19.5);
    assert_eq!((s.film.xres, s.film.yres), (1024, 1024));
    assert_eq!(s.film.filename.as_deref(), Some("cornell-box.png"));
    assert_eq!(s.filter, FilterDesc::Triangle { radius: Vec2::ONE });
    assert_eq!(
        (s.sampler.name.as_str(), s.sampler.pixel_samples),
        ("sobol", 64)
    );
    assert_eq!(s.integrator.name, "path");
    assert_eq!(s.integrator.loc.as_ref().unwrap().line, 1);
    let mut ip = s.integrator.params.clone();
    assert!(
        ip.check_unused().is_err(),
        "the loader must leave integrator params unread"
    );
    assert_eq!(ip.get_int("maxdepth", 5).unwrap(), 65);
    ip.check_unused().unwrap();
    // Shading normals as given (unit, the floor's is +y).
    let floor = &s.meshes[0];
    assert_vec(floor.normals.as_ref().unwrap()[0], Vec3::Y, 1e-6);
    assert_eq!(floor.uvs.as_ref().unwrap()[2], Vec2::new(1.0, 1.0));
}

#[test]
fn veach_mis_loads() {
    let path = shared("veach-mis/scene-v4.pbrt");
    let text = std::fs::read_to_string(&path).unwrap();
    let s = load(&path).unwrap_or_else(|e| panic!("{e}"));

    let n_area = text.matches("AreaLightSource").count();
    assert_eq!(n_area, 3, "the shared copy has three sphere lights");
    assert_eq!(s.lights.len(), n_area);
    // (centre, radius, L) read off the file by hand.
    let want = [
        (Vec3::new(0.0, 6.5, -2.8), 1.0, 7.599088),
        (Vec3::new(0.0, 6.5, 0.0), 0.5, 30.396353),
        (Vec3::new(0.0, 6.5, 2.7), 0.05, 3039.6353),
    ];
    for (light, (c, r, lv)) in s.lights.iter().zip(want) {
        let Light::Area { mesh, l, .. } = light else {
            panic!("{light:?}")
        };
        assert_eq!(*l, Vec3::splat(lv));
        let m = &s.meshes[*mesh as usize];
        let (mc, mr) = m.sphere.expect("sphere light keeps its analytic sphere");
        assert_vec(mc, c, 1e-6);
        assert!(close(mr, r, 1e-6));
        let area: f64 = (0..m.indices.len() as u32).map(|t| m.area(t) as f64).sum();
        let exact = 4.0 * std::f64::consts::PI * (r as f64).powi(2);
        let rel = (area - exact).abs() / exact;
        assert!(rel < 1e-3, "tessellated area off by {rel}");
        for p in &m.positions {
            assert!(((*p - c).length() - r).abs() < 1e-5 * r.max(1.0));
        }
    }
    // Conductors, copper RGB, alpha = roughness since remaproughness is false.
    let mut alphas: Vec<f32> = s
        .materials
        .iter()
        .filter_map(conductor)
        .map(|(eta, k, alpha_u, alpha_v)| {
            assert_eq!(eta, Vec3::new(0.200438, 0.924033, 1.102212));
            assert_eq!(k, Vec3::new(3.912949, 2.452848, 2.142188));
            assert_eq!(alpha_u, alpha_v);
            alpha_u
        })
        .collect();
    alphas.sort_by(f32::total_cmp);
    assert_eq!(alphas, vec![0.01, 0.05, 0.1, 0.25]);
    assert_eq!((s.film.xres, s.film.yres), (1280, 720));
    assert!(close(s.camera.fov_deg, 20.114292, 1e-7));
    // Camera: Transform column 3 is (0, -3.5, 28.2792); the camera sits where it maps to 0.
    let cam_from_world = s.camera.world_from_camera.inverse();
    let eye = s.camera.world_from_camera.transform_point3(Vec3::ZERO);
    assert_vec(cam_from_world.transform_point3(eye), Vec3::ZERO, 1e-4);
    assert_vec(eye, Vec3::new(28.2792, 3.5, 0.0), 1e-3);
}

#[test]
fn cornell_spheres_loads() {
    let path = shared("cornell-spheres/scene.pbrt");
    let s = load(&path).unwrap_or_else(|e| panic!("{e}"));
    let plys: Vec<_> = s
        .meshes
        .iter()
        .filter(|m| m.indices.len() == 20480)
        .collect();
    assert_eq!(plys.len(), 2);
    assert_eq!(s.triangle_count(), 5 * 2 + 2 * 20480 + 2);
    for m in plys {
        assert_eq!(m.positions.len(), 10242);
        let (lo, hi) = m.positions.iter().fold(
            (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
            |(lo, hi), p| (lo.min(*p), hi.max(*p)),
        );
        let c = 0.5 * (lo + hi);
        for p in &m.positions {
            let d = (*p - c).length();
            assert!((d - 0.1).abs() < 1e-4, "vertex at distance {d} from {c:?}");
        }
        // resting on the floor (the file leaves a 0.5 mm gap)
        assert!(lo.y >= 0.0 && lo.y < 1e-3, "lowest point {}", lo.y);
        assert!(m.normals.is_none() && m.sphere.is_none());
    }
    let glass = dielectric(1.5);
    assert!(s.materials.contains(&glass));
    let mirror = s
        .materials
        .iter()
        .find_map(conductor)
        .map(|(eta, k, alpha_u, _)| (eta, k, alpha_u));
    let (eta, k, alpha) = mirror.expect("mirror conductor");
    assert_eq!(eta, Vec3::ONE);
    let k_expect = 2.0 * (1.0f64 - 1e-7).sqrt() / 1e-7f64.sqrt();
    assert!(close(k.x, k_expect as f32, 1e-3), "k {k:?} vs {k_expect}");
    assert_eq!(alpha, 0.0);
    // Scale -1 1 1 before LookAt: camera +x is world +x (red wall on the left of the image).
    let cam = s.camera.world_from_camera;
    assert_vec(
        cam.transform_point3(Vec3::ZERO),
        Vec3::new(0.0, 0.28, 1.08),
        1e-6,
    );
    assert_vec(
        cam.transform_vector3(Vec3::Z),
        Vec3::new(0.0, 0.0, -1.0),
        1e-6,
    );
    assert_vec(cam.transform_vector3(Vec3::X), Vec3::X, 1e-6);
    assert_vec(cam.transform_vector3(Vec3::Y), Vec3::Y, 1e-6);
    assert_eq!(
        s.filter,
        FilterDesc::Box {
            radius: Vec2::splat(0.5)
        }
    );
    assert_eq!(s.lights.len(), 1);
    assert!(matches!(s.lights[0], Light::Area { l, .. } if l == Vec3::splat(20.0)));
}

#[test]
fn shared_scenes_load_quickly() {
    for p in [
        "cornell-box/scene-v4.pbrt",
        "veach-mis/scene-v4.pbrt",
        "cornell-spheres/scene.pbrt",
    ] {
        let t = std::time::Instant::now();
        let s = load(&shared(p)).unwrap();
        let ms = t.elapsed().as_secs_f64() * 1e3;
        println!("load {p}: {ms:.2} ms, {} triangles", s.triangle_count());
    }
}

#[test]
fn never_panics_on_cut_or_mangled_input() {
    let text = std::fs::read(shared("cornell-box/scene-v4.pbrt")).unwrap();
    let dir = TempDir::new("photon-parser");
    let path = dir.0.join("fuzz.pbrt");
    let mut loaded = 0;
    for cut in (0..text.len()).step_by(37) {
        std::fs::write(&path, &text[..cut]).unwrap();
        if load(&path).is_ok() {
            loaded += 1;
        }
    }
    // A simple LCG flips bytes to characters that matter to the syntax.
    let mut state = 12345u64;
    let specials = b"[]\"#\n -.e0x";
    for _ in 0..300 {
        let mut t = text.clone();
        for _ in 0..3 {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let at = (state >> 33) as usize % t.len();
            t[at] = specials[(state >> 20) as usize % specials.len()];
        }
        std::fs::write(&path, &t).unwrap();
        let _ = load(&path);
    }
    // Files cut before WorldBegin fail; the complete file loads.
    assert!(loaded < text.len() / 37);
    std::fs::write(&path, &text).unwrap();
    assert!(load(&path).is_ok());
}

#[test]
fn multi_megabyte_scene_loads() {
    // 200k points (about 7 MB of text), with comments and line breaks inside the lists.
    let n = 200_000usize;
    let mut src = String::from("WorldBegin\nShape \"trianglemesh\" \"point3 P\" [\n");
    for i in 0..n {
        let v = i as f32 * 0.25;
        src.push_str(&format!("{v} {} -{v} # point {i}\n", i % 7));
    }
    src.push_str("] \"integer indices\" [\n");
    for i in 0..n - 2 {
        src.push_str(&format!("{i} {} {}\n", i + 1, i + 2));
    }
    src.push_str("]\n");
    let dir = TempDir::new("photon-parser");
    let path = dir.write("big.pbrt", &src);
    let t = std::time::Instant::now();
    let s = load(&path).unwrap_or_else(|e| panic!("{e}"));
    let secs = t.elapsed().as_secs_f64();
    println!(
        "{:.1} MB loaded in {:.1} ms ({:.0} MB/s)",
        src.len() as f64 / 1e6,
        secs * 1e3,
        src.len() as f64 / 1e6 / secs
    );
    let m = only_mesh(&s);
    assert_eq!(m.indices.len(), n - 2);
    assert_eq!(m.indices[1234], [1234, 1235, 1236]);
    assert_eq!(m.positions[1001], Vec3::new(250.25, 0.0, -250.25));
}

#[test]
fn param_set_is_clone_debug_send_sync() {
    fn check<T: Clone + std::fmt::Debug + Send + Sync>() {}
    check::<photon::scene::ParamSet>();
    check::<Scene>();
}

#[test]
fn repo_scenes_load() {
    let mut n = 0;
    for entry in std::fs::read_dir("scenes").unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "pbrt") {
            let s = load(&path).unwrap_or_else(|e| panic!("{e}"));
            assert!(
                s.triangle_count() > 0 && !s.lights.is_empty(),
                "{}",
                path.display()
            );
            n += 1;
        }
    }
    assert!(n > 0, "no scenes in scenes/");
}

/// The loader's memory budget gives back what a failed read reserved, keeps what a loaded
/// mesh or image holds, and refuses what passes its limit (issue 22).
#[test]
fn load_budget_accounts_for_failed_and_finished_reads() {
    use photon::scene::loader::{ply::read_ply, textures::read_image, LoadBudget};
    use photon::texture::Encoding;
    let dir = TempDir::new("photon-budget");
    let budget = LoadBudget::new(1 << 30);
    // A truncated PLY (its counts need more data than it holds) and a corrupt PNG.
    dir.write(
        "short.ply",
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
         property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n",
    );
    assert!(read_ply(&dir.0.join("short.ply"), &budget).is_err());
    assert_eq!(budget.held(), 0, "a failed PLY read keeps nothing");
    let mut png = Vec::new();
    image::RgbImage::new(4, 4)
        .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
        .unwrap();
    png.truncate(png.len() - 20);
    std::fs::write(dir.0.join("bad.png"), &png).unwrap();
    assert!(read_image(&dir.0.join("bad.png"), Encoding::Srgb, &budget).is_err());
    assert_eq!(budget.held(), 0, "a failed decode keeps nothing");
    // A good mesh keeps 32 B a vertex and 24 B a face; a good 4x4 image 12 B a texel.
    dir.write(
        "tri.ply",
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
         property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n\
         0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n",
    );
    read_ply(&dir.0.join("tri.ply"), &budget).unwrap();
    assert_eq!(budget.held(), 3 * 32 + 24);
    let good = dir.0.join("good.png");
    image::RgbImage::new(4, 4).save(&good).unwrap();
    let fresh = LoadBudget::new(1 << 30);
    read_image(&good, Encoding::Srgb, &fresh).unwrap();
    assert_eq!(fresh.held(), 16 * 12);
    // The decode's peak was reserved first: 16 texels x (3 + 12 + 12) B.
    assert_eq!(fresh.peak(), 16 * 27);
    let tight = LoadBudget::new(100);
    let err = read_image(&good, Encoding::Srgb, &tight).unwrap_err();
    assert!(err.contains("decoding it needs 432 B"), "{err}");
    assert_eq!(tight.held(), 0);
}
