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
