//! The force-displacement outputs of a stepped contact run: the CSV and its PNG plot, and a run
//! that cannot draw the plot (no font) still succeeds with the CSV and a warning.

mod common;

use common::case_builder::CaseFile;
use common::run_solve_with;

/// The half-disc pressed onto the block (level-0 fixture) in two load steps.
fn stepped_half_disc() -> CaseFile {
    common::half_disc_on_block("half_disc_on_block.msh").load_steps(&[0.5, 1.0])
}

#[test]
fn stepped_contact_writes_the_csv_and_a_png_plot_of_it() {
    let (dir, path) = stepped_half_disc().write();
    let output = run_solve_with(&path, &[]);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "{stderr}");
    assert!(!stderr.contains("warning"), "{stderr}");
    let csv = std::fs::read_to_string(dir.path().join("out/force_displacement.csv")).unwrap();
    assert_eq!(csv.lines().count(), 3, "{csv}");

    // A PNG by its signature and header, then decoded in full by an independent decoder.
    let bytes = std::fs::read(dir.path().join("out/force_displacement.png")).unwrap();
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n", "PNG signature");
    assert_eq!(&bytes[12..16], b"IHDR", "the first chunk is the header");
    let width = u32::from_be_bytes(bytes[16..20].try_into().unwrap());
    let height = u32::from_be_bytes(bytes[20..24].try_into().unwrap());
    assert_eq!((width, height), internodes::output::PLOT_SIZE);
    let mut reader = png::Decoder::new(std::io::Cursor::new(&bytes))
        .read_info()
        .expect("a decodable PNG header");
    let mut pixels = vec![0; reader.output_buffer_size()];
    let frame = reader
        .next_frame(&mut pixels)
        .expect("decodable image data");
    assert_eq!((frame.width, frame.height), (width, height));
    // Something was drawn: axes, labels and curves are not white.
    let drawn = pixels[..frame.buffer_size()]
        .chunks(frame.color_type.samples())
        .filter(|p| p.iter().any(|&c| c < 200))
        .count();
    let total = (width * height) as usize;
    assert!(
        drawn > total / 200 && drawn < total / 2,
        "{drawn} of {total} pixels drawn"
    );
}

#[test]
fn without_a_font_the_run_succeeds_with_the_csv_and_a_warning() {
    let (dir, path) = stepped_half_disc().write();
    let missing = dir.path().join("no-such-font.ttf");
    let output = run_solve_with(
        &path,
        &[("INTERNODES_PLOT_FONT", missing.to_str().unwrap())],
    );
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "{stderr}");
    assert!(
        stderr.contains("warning") && stderr.contains(missing.to_str().unwrap()),
        "the warning names the missing font: {stderr}"
    );
    assert!(dir.path().join("out/force_displacement.csv").is_file());
    assert!(dir.path().join("out/summary.json").is_file());
    assert!(!dir.path().join("out/force_displacement.png").exists());
}

#[test]
fn a_file_that_is_not_a_font_is_reported() {
    let (dir, path) = stepped_half_disc().write();
    let output = run_solve_with(&path, &[("INTERNODES_PLOT_FONT", path.to_str().unwrap())]);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "{stderr}");
    assert!(
        stderr.contains("is not a TrueType/OpenType font"),
        "{stderr}"
    );
    assert!(!dir.path().join("out/force_displacement.png").exists());
}
