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

/// The pixels of the force panel (the left half) drawn in the force curve's colour.
fn force_curve_pixels(png_path: &std::path::Path) -> usize {
    let bytes = std::fs::read(png_path).unwrap();
    let mut reader = png::Decoder::new(std::io::Cursor::new(&bytes))
        .read_info()
        .unwrap();
    let mut pixels = vec![0; reader.output_buffer_size()];
    let frame = reader.next_frame(&mut pixels).unwrap();
    let samples = frame.color_type.samples();
    use plotters::style::{Color, Palette, Palette99};
    let colour = Palette99::pick(0).to_rgba();
    let rgb = [colour.0, colour.1, colour.2];
    let width = frame.width as usize;
    (pixels[..frame.buffer_size()].chunks(samples).enumerate())
        .filter(|(i, p)| i % width < width / 2 && p[..3] == rgb)
        .count()
}

#[test]
fn one_load_step_is_a_dot_not_a_line_from_the_origin() {
    // A line from the origin to the only point would draw a linear law: one step is one dot,
    // two steps a dot each and the segment between them.
    let count = |case: CaseFile| {
        let (dir, path) = case.write();
        let output = run_solve_with(&path, &[]);
        assert!(output.status.success());
        force_curve_pixels(&dir.path().join("out/force_displacement.png"))
    };
    let one = count(common::half_disc_on_block("half_disc_on_block.msh"));
    let two = count(stepped_half_disc());
    // A filled dot of radius 4 covers about 50 pixels.
    assert!(one > 20 && one < 120, "one step: {one} pixels");
    assert!(
        two > 2 * one + 50,
        "two steps: {two} pixels against {one} for one"
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
