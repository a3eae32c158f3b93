//! Case 9 of issue 10: a SIGINT/SIGTERM while the outputs are written removes the temporaries
//! and replaces nothing. Alone in its test binary because the interrupt flag is process-wide.
use photon::interrupt::{self, Signal};
use photon::tools::output::{OutputError, Outputs, Writer};
use std::path::Path;

#[test]
fn case_09_a_signal_while_writing_leaves_no_temp_and_no_mixed_outputs() {
    let d = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("output_signal");
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    let (exr, png) = (d.join("out.exr"), d.join("out.png"));
    std::fs::write(&exr, "old exr").unwrap();
    std::fs::write(&png, "old png").unwrap();
    let outputs = Outputs::plan(&exr, Some(&png)).unwrap();
    // The EXR temp is complete; the signal arrives while the PNG is being written.
    let first: Writer =
        Box::new(|p: &Path| std::fs::write(p, "new exr").map_err(|e| e.to_string()));
    let second: Writer = Box::new(|p: &Path| {
        std::fs::write(p, "half a png").unwrap();
        interrupt::raise(Signal::Terminate);
        Ok(())
    });
    let e = outputs.commit(vec![first, second]).unwrap_err();
    assert_eq!(e, OutputError::Interrupted(Signal::Terminate));
    assert_eq!(Signal::Terminate.exit_code(), 143);
    assert!(e.to_string().contains("SIGTERM"), "{e}");
    assert_eq!(std::fs::read_to_string(&exr).unwrap(), "old exr");
    assert_eq!(std::fs::read_to_string(&png).unwrap(), "old png");
    let mut names: Vec<String> = std::fs::read_dir(&d)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(names, ["out.exr", "out.png"], "no temporary file is left");
}

/// SIGTERM sent to a real render at some point after it starts: whatever phase it reaches
/// (rendering: the default action, no temporary exists yet; writing: temporaries removed, exit
/// 143; done: exit 0), no temporary file is left and the outputs are either the old ones or
/// complete new ones. Deterministic in what it checks, whatever the timing.
#[test]
fn sigterm_during_a_render_leaves_no_temporary() {
    use std::io::{BufRead, BufReader};
    use std::os::unix::process::ExitStatusExt;
    let d = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("output_sigterm");
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    let (exr, png) = (d.join("out.exr"), d.join("out.png"));
    for delay_ms in [0u64, 50, 300] {
        std::fs::write(&exr, "old exr").unwrap();
        std::fs::write(&png, "old png").unwrap();
        let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_photon"))
            .args(["render", "../shared/scenes/cornell-box/scene-v4.pbrt"])
            .args(["--res", "128x128", "--spp", "4", "--threads", "1", "-o"])
            .arg(&exr)
            .arg("--png")
            .arg(&png)
            .stdout(std::process::Stdio::piped())
            .stderr(std::process::Stdio::null())
            .spawn()
            .unwrap();
        let mut lines = BufReader::new(child.stdout.take().unwrap()).lines();
        for line in lines.by_ref() {
            if line.unwrap().starts_with("render:") {
                break;
            }
        }
        std::thread::sleep(std::time::Duration::from_millis(delay_ms));
        let _ = std::process::Command::new("kill")
            .args(["-TERM", &child.id().to_string()])
            .status();
        for _ in lines {}
        let st = child.wait().unwrap();
        // A render stopped while rendering keeps its finished tiles in the temporary directory.
        for name in ["out.exr", "out.png"] {
            let kept = std::env::temp_dir().join(format!("photon-{}-{name}", child.id()));
            let _ = std::fs::remove_file(kept);
        }
        println!("delay {delay_ms} ms: {st:?}");
        assert!(
            st.signal() == Some(15) || st.code() == Some(143) || st.code() == Some(0),
            "{st:?}"
        );
        let names: Vec<String> = std::fs::read_dir(&d)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        assert_eq!(names.len(), 2, "temporary files left: {names:?}");
        let new_exr = photon::imageio::read_exr(&exr).is_ok();
        let old_exr = std::fs::read(&exr).unwrap() == b"old exr";
        let old_png = std::fs::read(&png).unwrap() == b"old png";
        if st.code() == Some(0) {
            assert!(new_exr && !old_png);
        } else {
            assert!(old_exr && old_png, "a stopped render replaced an output");
        }
    }
}
