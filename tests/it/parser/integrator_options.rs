//! `Integrator` parameters (each integrator reads its own, foreign ones noted or rejected) and
//! the directives accepted with a note (`Accelerator`, `Option`, `ColorSpace`).

use super::*;

#[test]
fn accelerator_option_colorspace_are_accepted_with_notes() {
    let s = ok(
        r#"Accelerator "bvh" "integer maxnodeprims" 4 "string splitmethod" "sah"
Option "bool wavefront" true
ColorSpace "srgb"
WorldBegin
MediumInterface "" ""
ColorSpace "srgb"
"#,
    );
    assert_eq!(s.notes.len(), 2, "{:?}", s.notes);
    assert!(s.notes[0].contains("scene.pbrt:1:1: Accelerator \"bvh\""));
    assert!(s.notes[0].contains("\"integer maxnodeprims\", \"string splitmethod\""));
    assert!(s.notes[1].contains(":2:8: Option \"bool wavefront\" ignored"));
    assert_src_err(
        "WorldBegin\nAccelerator \"bvh\"\n",
        2,
        &["Accelerator is not allowed after WorldBegin"],
    );
    assert_src_err("\nColorSpace \"aces2065-1\"\n", 2, &["\"aces2065-1\""]);
    assert_src_err(
        "Option \"bool forcediffuse\" true\n",
        1,
        &["\"bool forcediffuse\": unsupported Option"],
    );
}

#[test]
fn other_integrators_parameters_are_ignored_with_a_note() {
    let s = ok(
        r#"Integrator "sppm" "float radius" 0.01 "integer maxdepth" 7
    "integer photonsperiteration" 1000
WorldBegin
"#,
    );
    assert_eq!(s.notes.len(), 1, "{:?}", s.notes);
    assert!(
        s.notes[0].ends_with("ignores \"float radius\", \"integer photonsperiteration\""),
        "{}",
        s.notes[0]
    );
    // maxdepth stays for the render to read, and nothing else is left unread.
    let mut p = s.integrator.params.clone();
    assert!(p.check_unused().is_err());
    assert_eq!(p.get_int("maxdepth", 5).unwrap(), 7);
    p.check_unused().unwrap();
    // "regularize" of volpath too; a parameter volpath does not have stays unread (an error
    // when the render reads the settings).
    let s = ok("Integrator \"volpath\" \"bool regularize\" true \"float radius\" 1\nWorldBegin\n");
    assert!(s.notes[0].contains("\"bool regularize\""));
    let e = photon::integrator::RenderSettings::from_scene(&s).unwrap_err();
    assert!(
        e.to_string().contains("unused parameter \"float radius\""),
        "{e}"
    );
    // The photon mapper's own parameters are not "foreign".
    let s = ok("Integrator \"photonmap\" \"integer globalphotons\" 10\nWorldBegin\n");
    assert!(s.notes.is_empty());
    let settings = photon::integrator::RenderSettings::from_scene(&s).unwrap();
    assert_eq!(settings.photon.trace.global_photons, 10);
}

/// Each integrator reads its own parameters: the photon mapper's on another integrator's line
/// are an error at the parameter (they rendered silently before, issue 16), whichever
/// integrator the command line then picks.
#[test]
fn photon_map_parameters_belong_to_the_photonmap_line() {
    for (line, key) in [
        (
            "Integrator \"path\"\n  \"integer globallookup\" [ 7 ] \"bool progressive\" true",
            "globallookup",
        ),
        (
            "Integrator \"sppm\" \"bool progressive\" true",
            "progressive",
        ),
        ("Integrator \"volpath\" \"float alpha\" 0.5", "alpha"),
    ] {
        let s = ok(&format!("{line}\nWorldBegin\n"));
        let e = photon::integrator::RenderSettings::from_scene(&s).unwrap_err();
        let row = if key == "globallookup" { 2 } else { 1 };
        assert!(
            e.to_string().contains(&format!("scene.pbrt:{row}:"))
                && e.to_string().contains(&format!(
                    "\"{key}\" is a parameter of Integrator \"photonmap\""
                )),
            "{e}"
        );
    }
    // maxdepth and passspp belong to every integrator.
    let s = ok("Integrator \"path\" \"integer maxdepth\" 3 \"integer passspp\" 2\nWorldBegin\n");
    let settings = photon::integrator::RenderSettings::from_scene(&s).unwrap();
    assert_eq!((settings.max_depth, settings.pass_spp), (3, 2));
}
