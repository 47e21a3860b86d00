//! Frames read back as written; previews are pictures of the particles.

use coil::output::preview::{render, render_frame, Coloring, View};
use coil::output::vtu::{encode, Field};
use coil::output::vtu_read::parse;
use coil::scene::VtuEncoding;

use crate::common;

/// The arguments of `coil run scenes/dam_break.toml --quiet --out OUT`, with `--set` before
/// each of `settings`.
fn dam_break_run(out: &std::path::Path, settings: &[&str]) -> Vec<String> {
    let scene = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/dam_break.toml");
    let mut args = vec!["run".into(), scene.display().to_string(), "--quiet".into(), "--out".into(), out.display().to_string()];
    args.extend(settings.iter().flat_map(|s| ["--set".to_string(), s.to_string()]));
    args
}

/// Positions, velocities, viscosities and ids of a test cloud.
type Cloud = (Vec<[f64; 3]>, Vec<[f32; 3]>, Vec<f32>, Vec<u32>);

fn cloud(n: usize) -> Cloud {
    // A helix, so side and top views differ.
    let position = (0..n).map(|k| {
        let t = k as f64 * 0.05;
        [0.1 * t.cos(), 0.002 * t, 0.1 * t.sin()]
    });
    let velocity = (0..n).map(|k| [k as f32, -(k as f32), 0.5]);
    let viscosity = (0..n).map(|k| 0.01 + 0.09 * k as f32 / n as f32);
    (position.collect(), velocity.collect(), viscosity.collect(), (0..n as u32).map(|k| 7 * k + 3).collect())
}

/// The cloud as a `.vtu` file's bytes, in `encoding`.
fn encoded(position: &[[f64; 3]], velocity: &[[f32; 3]], viscosity: &[f32], id: &[u32], encoding: VtuEncoding) -> Vec<u8> {
    let mut bytes = Vec::new();
    encode(
        position,
        &[Field::Vector("velocity", velocity), Field::Scalar("viscosity", viscosity), Field::Id("id", id)],
        encoding,
        &mut bytes,
    );
    bytes
}

#[test]
fn a_frame_written_and_read_back_gives_the_same_particles() {
    let (position, velocity, viscosity, id) = cloud(1000);
    for encoding in [VtuEncoding::Raw, VtuEncoding::Base64] {
        let bytes = encoded(&position, &velocity, &viscosity, &id, encoding);
        let frame = parse(&bytes).expect("own format");
        // Bit for bit: positions are written as f64, the fields as the f32 they are.
        assert_eq!(frame.position, position, "{encoding:?}");
        assert_eq!(frame.vectors["velocity"], velocity, "{encoding:?}");
        assert_eq!(frame.scalars["viscosity"], viscosity, "{encoding:?}");
        assert_eq!(frame.id, id, "{encoding:?}");
        let torn = &bytes[..bytes.len() / 2];
        assert!(parse(torn).is_err(), "{encoding:?}: a torn file is refused, not misread");
    }
}

#[test]
fn preview_has_the_expected_size_and_shows_the_particles() {
    let (position, velocity, viscosity, id) = cloud(2000);
    let size = 200;
    let image = render(&position, &viscosity, (0.01, 0.1), View::Both, size);
    assert_eq!((image.width, image.height), (2 * size + 110, size));
    let panel_ink = |left: usize| {
        (0..size * size)
            .filter(|&k| {
                let (x, y) = (left + k % size, k / size);
                image.pixels[3 * (y * image.width + x)..][..3] != [255, 255, 255]
            })
            .count()
    };
    // A helix of 2000 points covers a few % of each panel; a blank panel has no ink at all.
    let (side, top) = (panel_ink(0), panel_ink(size));
    assert!(side > size * size / 100 && top > size * size / 100, "side {side} top {top} inked pixels");
    // Colour follows viscosity: the low end is dark purple, the high end yellow.
    let distinct: std::collections::HashSet<&[u8]> = image.pixels.chunks(3).collect();
    assert!(distinct.len() > 50, "{} colours", distinct.len());

    // The PNG decodes to the same picture.
    let png = image.to_png();
    let decoder = png::Decoder::new(std::io::Cursor::new(png));
    let mut reader = decoder.read_info().expect("valid PNG");
    let mut buf = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut buf).expect("a frame");
    assert_eq!((info.width as usize, info.height as usize), (image.width, image.height));
    assert_eq!(&buf[..info.buffer_size()], &image.pixels[..]);

    // From a frame: coloured by speed as well.
    let frame = parse(&encoded(&position, &velocity, &viscosity, &id, VtuEncoding::Raw)).expect("own format");
    let by_speed = render_frame(&frame, View::Side, Coloring::Speed, None, size).expect("has velocity");
    assert_eq!((by_speed.width, by_speed.height), (size + 110, size));
    assert_ne!(by_speed.pixels, render_frame(&frame, View::Side, Coloring::Viscosity, None, size).expect("has viscosity").pixels);
}

#[test]
fn a_run_killed_mid_write_leaves_only_whole_frames() {
    let dir = std::env::temp_dir().join(format!("coil-kill-{}", std::process::id()));
    let out = dir.join("out");
    std::fs::create_dir_all(&dir).expect("temp dir");
    // A frame every step, so the kill is likely to land inside a write.
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_coil"))
        .args(dam_break_run(&out, &["output.every_steps=1"]))
        .spawn()
        .expect("coil starts");
    let frames = |out: &std::path::Path| {
        std::fs::read_dir(out)
            .map(|d| d.filter_map(|e| e.ok()).filter(|e| e.path().extension().is_some_and(|x| x == "vtu")).count())
            .unwrap_or(0)
    };
    let started = std::time::Instant::now();
    while frames(&out) < 6 && started.elapsed() < std::time::Duration::from_secs(60) {
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    child.kill().expect("kill");
    child.wait().expect("reaped");
    let mut whole = 0;
    for entry in std::fs::read_dir(&out).expect("out") {
        let path = entry.expect("entry").path();
        if path.extension().is_some_and(|x| x == "vtu") {
            coil::output::vtu_read::read_frame(&path).unwrap_or_else(|e| panic!("torn frame: {e}"));
            whole += 1;
        }
    }
    assert!(whole >= 6, "{whole} frames before the kill");
    // The series names only frames that exist, whole.
    let pvd = std::fs::read_to_string(out.join("dam_break.pvd")).expect("series");
    for file in pvd.split("file=\"").skip(1).map(|s| &s[..s.find('"').expect("closing quote")]) {
        assert!(out.join(file).is_file(), "{file} listed but missing");
    }
    let log: serde_json::Value = serde_json::from_slice(&std::fs::read(out.join("run.json")).expect("log")).expect("whole JSON");
    assert_eq!(log["status"], "running", "killed before the end");
    std::fs::remove_dir_all(&dir).ok();
}

/// Runs `coil` with `args`, sends it SIGINT (Ctrl-C) once `out` holds its fourth frame, and
/// returns how it ended, with its stderr.
#[cfg(unix)]
fn interrupted_run(args: &[String], out: &std::path::Path) -> std::process::Output {
    let child = std::process::Command::new(env!("CARGO_BIN_EXE_coil"))
        .args(args)
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("coil starts");
    let started = std::time::Instant::now();
    while !out.join("frame_000003.vtu").is_file() && started.elapsed() < std::time::Duration::from_secs(60) {
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    let sent = std::process::Command::new("kill").args(["-s", "INT", &child.id().to_string()]).status().expect("kill runs");
    assert!(sent.success());
    child.wait_with_output().expect("reaped")
}

/// Ctrl-C (SIGINT) stops a run after its step: exit code 130, the log says "interrupted" with
/// the summary, and every frame written is kept and listed.
#[cfg(unix)]
#[test]
fn an_interrupted_run_logs_its_summary_and_keeps_its_frames() {
    let dir = std::env::temp_dir().join(format!("coil-interrupt-{}", std::process::id()));
    let out = dir.join("out");
    let ended = interrupted_run(&dam_break_run(&out, &["output.every_steps=5"]), &out);
    let stderr = String::from_utf8_lossy(&ended.stderr);
    assert_eq!(ended.status.code(), Some(130), "{stderr}");
    assert!(stderr.contains("interrupted at step"), "{stderr}");
    let log: serde_json::Value = serde_json::from_slice(&std::fs::read(out.join("run.json")).expect("log")).expect("whole JSON");
    assert_eq!(log["status"], "interrupted");
    let frames = log["summary"]["frames"].as_u64().expect("a summary with its frames");
    let on_disk = std::fs::read_dir(&out)
        .expect("out")
        .filter(|e| e.as_ref().is_ok_and(|e| e.file_name().to_string_lossy().starts_with("frame_")))
        .count() as u64;
    let pvd = std::fs::read_to_string(out.join("dam_break.pvd")).expect("series");
    assert!(frames >= 4 && on_disk == frames && pvd.matches("<DataSet").count() as u64 == frames, "{frames} {on_disk} {pvd}");
    assert!(log["summary"]["simulated_s"].as_f64().expect("time") < 1.0, "stopped before the end");
    std::fs::remove_dir_all(&dir).ok();
}

/// `output.vtu_encoding = "base64"` writes frames that a reader other than coil's opens
/// (vtkio, which splashsurf reads frames with, and which refuses raw appended data), with
/// every value that the raw frame of the same run holds.
#[test]
fn base64_frames_open_in_an_independent_reader_with_the_raw_frames_values() {
    use vtkio::model::{Attribute, DataSet, IOBuffer, Piece};
    let dir = std::env::temp_dir().join(format!("coil-base64-{}", std::process::id()));
    let (raw, base64) = (dir.join("raw"), dir.join("base64"));
    for (out, encoding) in [(&raw, "raw"), (&base64, "base64")] {
        let set = format!("output.vtu_encoding={encoding}");
        let ran = common::coil(&dam_break_run(out, &["simulation.end_time_s=0.0004", "output.every_steps=1", &set]));
        assert!(ran.status.success(), "{}", String::from_utf8_lossy(&ran.stderr));
    }
    let frame = |dir: &std::path::Path| coil::output::vtu_read::read_frame(&dir.join("frame_000001.vtu")).expect("a frame");
    let expected = frame(&raw);
    assert_eq!(frame(&base64), expected, "coil reads the base64 frame as the raw one");
    let vtk = vtkio::Vtk::import(base64.join("frame_000001.vtu")).expect("vtkio reads the base64 frame");
    let DataSet::UnstructuredGrid { pieces, .. } = vtk.data else { panic!("not an unstructured grid") };
    let Some(Piece::Inline(piece)) = pieces.into_iter().next() else { panic!("no inline piece") };
    let IOBuffer::F64(points) = &piece.points else { panic!("positions not f64: {:?}", piece.points.scalar_type()) };
    assert_eq!(points.chunks(3).map(|p| [p[0], p[1], p[2]]).collect::<Vec<_>>(), expected.position);
    let density = piece.data.point.iter().find_map(|a| match a {
        Attribute::DataArray(array) if array.name == "density" => Some(&array.data),
        _ => None,
    });
    let Some(IOBuffer::F32(density)) = density else { panic!("no f32 density array") };
    assert_eq!(density, &expected.scalars["density"]);
    assert!(vtkio::Vtk::import(base64.join("boundary.vtu")).is_ok(), "the walls' frame");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn frames_also_as_binary_ply_and_splashsurf_xyz() {
    let dir = std::env::temp_dir().join(format!("coil-formats-{}", std::process::id()));
    let out = common::coil(&dam_break_run(&dir, &["simulation.end_time_s=0.0004", r#"output.formats=["vtu", "ply", "xyz"]"#]));
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let frame = coil::output::vtu_read::read_frame(&dir.join("frame_000000.vtu")).expect("vtu");
    let n = frame.position.len();
    let xyz = std::fs::read(dir.join("frame_000000.xyz")).expect("xyz");
    assert_eq!(xyz.len(), 12 * n);
    let first: Vec<f32> = xyz[..12].chunks(4).map(|c| f32::from_ne_bytes(c.try_into().expect("4 bytes"))).collect();
    assert_eq!(first, frame.position[0].map(|x| x as f32));
    let ply = std::fs::read(dir.join("frame_000000.ply")).expect("ply");
    let end = ply.windows(11).position(|w| w == b"end_header\n").expect("a PLY header") + 11;
    let header = String::from_utf8_lossy(&ply[..end]);
    assert!(header.starts_with("ply\nformat binary_little_endian 1.0\n") && header.contains(&format!("element vertex {n}\n")));
    // x y z vx vy vz density pressure viscosity shear_rate as float, id as uint.
    assert_eq!(ply.len() - end, 44 * n);
    let last_id = u32::from_le_bytes(ply[ply.len() - 4..].try_into().expect("4 bytes"));
    assert_eq!(last_id, frame.id[n - 1]);
    let series = dir.join("dam_break.pvd");
    assert!(series.is_file());
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.contains(&format!("(open {} in ParaView)", series.display())), "{stdout}");

    std::fs::remove_dir_all(&dir).ok();
    let ply_only = common::coil(&dam_break_run(&dir, &["simulation.end_time_s=0.0004", r#"output.formats=["ply"]"#]));
    assert!(ply_only.status.success(), "{}", String::from_utf8_lossy(&ply_only.stderr));
    let stdout = String::from_utf8_lossy(&ply_only.stdout);
    assert!(!series.exists() && !stdout.contains(".pvd"), "no series is written or named without .vtu frames: {stdout}");
    std::fs::remove_dir_all(&dir).ok();
}

/// Every file of a run's folder but its log and checkpoint (which hold wall times), by name.
fn run_files(dir: &std::path::Path) -> Vec<(String, Vec<u8>)> {
    let mut files: Vec<_> = std::fs::read_dir(dir)
        .expect("output folder")
        .map(|e| e.expect("entry").path())
        .filter(|p| !p.ends_with("run.json") && !p.ends_with("checkpoint.bin") && !p.ends_with("run.lock"))
        .map(|p| (p.file_name().expect("a name").to_string_lossy().into_owned(), std::fs::read(&p).expect("readable")))
        .collect();
    files.sort();
    files
}

fn run_log(dir: &std::path::Path) -> serde_json::Value {
    serde_json::from_slice(&std::fs::read(dir.join("run.json")).expect("log")).expect("whole JSON")
}

/// The simulated times (s) a `.pvd` series lists, in its order.
fn series_times(pvd: &std::path::Path) -> Vec<f64> {
    let text = std::fs::read_to_string(pvd).expect("series");
    text.split("timestep=\"").skip(1).map(|s| s[..s.find('"').expect("quote")].parse().expect("a time")).collect()
}

/// Ctrl-C, then `coil resume`: the frames and series come out byte for byte as from a run never
/// stopped, and the log's summary counts the whole run. A finished run goes further with a
/// later end time and not without one.
#[cfg(unix)]
#[test]
fn a_run_stopped_by_ctrl_c_resumes_to_the_frames_of_one_never_stopped() {
    let dir = std::env::temp_dir().join(format!("coil-resume-{}", std::process::id()));
    let (whole, stopped) = (dir.join("whole"), dir.join("stopped"));
    let settings = ["output.every_steps=20", "simulation.end_time_s=0.06"];
    let done = common::coil(&dam_break_run(&whole, &settings));
    assert!(done.status.success(), "{}", String::from_utf8_lossy(&done.stderr));

    let ended = interrupted_run(&dam_break_run(&stopped, &settings), &stopped);
    let stderr = String::from_utf8_lossy(&ended.stderr);
    assert_eq!(ended.status.code(), Some(130), "stopped before the end: {stderr}");
    assert!(stderr.contains(&format!("`coil resume {}` continues it", stopped.display())), "{stderr}");
    let at_stop = run_log(&stopped)["summary"]["steps"].as_u64().expect("steps");

    let out = common::coil(&["resume", stopped.to_str().expect("utf-8"), "--quiet"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let (a, b) = (run_files(&whole), run_files(&stopped));
    assert_eq!(a.iter().map(|f| &f.0).collect::<Vec<_>>(), b.iter().map(|f| &f.0).collect::<Vec<_>>());
    assert!(a.len() > 17 && a == b, "16 frames, the boundary and the series, byte for byte");
    let (log_a, log_b) = (run_log(&whole), run_log(&stopped));
    assert_eq!(log_b["status"], "completed");
    assert_eq!(log_b["resumed"][0]["step"].as_u64(), Some(at_stop), "{log_b}");
    for figure in ["steps", "frames", "simulated_s", "max_speed_m_s", "max_compression", "fluid_particles"] {
        assert_eq!(log_a["summary"][figure], log_b["summary"][figure], "{figure}");
    }

    let again = common::coil(&["resume", stopped.to_str().expect("utf-8"), "--quiet"]);
    let stderr = String::from_utf8_lossy(&again.stderr);
    assert_eq!(again.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("run.json: simulation.end_time_s: the run reached its end time t = 0.06 s"), "{stderr}");
    let earlier = common::coil(&["resume", stopped.to_str().expect("utf-8"), "--quiet", "--set", "simulation.end_time_s=0.03"]);
    let stderr = String::from_utf8_lossy(&earlier.stderr);
    assert!(
        earlier.status.code() == Some(2) && stderr.contains("must be later than the checkpoint's t = 0.060000 s, got 0.03"),
        "{stderr}"
    );

    let further = common::coil(&["resume", stopped.to_str().expect("utf-8"), "--quiet", "--set", "simulation.end_time_s=0.08"]);
    assert!(further.status.success(), "{}", String::from_utf8_lossy(&further.stderr));
    let log = run_log(&stopped);
    assert_eq!((log["summary"]["steps"].as_u64(), log["summary"]["frames"].as_u64()), (Some(400), Some(21)), "{log}");
    assert_eq!(log["scene"]["simulation"]["end_time_s"], 0.08);
    let extended = run_files(&stopped);
    for (name, bytes) in a.iter().filter(|f| f.0.starts_with("frame_")) {
        assert!(extended.iter().any(|(n, b)| n == name && b == bytes), "{name} rewritten by the extension");
    }
    let times = series_times(&stopped.join("dam_break.pvd"));
    assert!(times.len() == 21 && times.windows(2).all(|w| w[0] < w[1]) && times[20] == 0.08, "{times:?}");
    std::fs::remove_dir_all(&dir).ok();
}

/// A run resumed with another `output.every_s` writes its next frame that interval after its last
/// one, not at the interval it was stopped on.
#[test]
fn a_run_resumed_with_another_frame_interval_takes_it_up_at_once() {
    let dir = std::env::temp_dir().join(format!("coil-resume-every-{}", std::process::id()));
    let out = dir.join("run");
    let done = common::coil(&dam_break_run(&out, &["output.every_s=0.01", "simulation.end_time_s=0.02"]));
    assert!(done.status.success(), "{}", String::from_utf8_lossy(&done.stderr));
    let args = ["simulation.end_time_s=0.03", "output.every_s=0.0025"].map(|s| ["--set", s]).concat();
    let resumed = common::coil(&[&["resume", out.to_str().expect("utf-8"), "--quiet"][..], &args].concat());
    assert!(resumed.status.success(), "{}", String::from_utf8_lossy(&resumed.stderr));
    let times = series_times(&out.join("dam_break.pvd"));
    // The dam break steps at its Eq. (10) bound, 400 steps to 0.08 s (as the test above counts).
    let dt = 0.08 / 400.0;
    let due = [0.0, 0.01, 0.02, 0.0225, 0.025, 0.0275, 0.03];
    assert_eq!(times.len(), due.len(), "{times:?}");
    for (t, due) in times.iter().zip(due) {
        assert!(*t >= due - 1e-9 && *t < due + dt, "a frame at {t} s, due at {due} s: {times:?}");
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// `coil resume` refuses, naming the file and the reason, a folder that is not a run's, a
/// checkpoint cut short or missing, a log whose scene was edited since the checkpoint, and a
/// `--set` of the physics the checkpoint holds.
#[test]
fn resume_refuses_what_it_cannot_continue() {
    let dir = std::env::temp_dir().join(format!("coil-resume-refused-{}", std::process::id()));
    let out = dir.join("run");
    let done = common::coil(&dam_break_run(&out, &["simulation.end_time_s=0.002"]));
    assert!(done.status.success(), "{}", String::from_utf8_lossy(&done.stderr));
    let refused_with = |set: &str, expected: &str| {
        let r = common::coil(&["resume", out.to_str().expect("utf-8"), "--quiet", "--set", set]);
        let stderr = String::from_utf8_lossy(&r.stderr).into_owned();
        assert_eq!(r.status.code(), Some(2), "{stderr}");
        assert!(stderr.contains(expected), "expected `{expected}` in: {stderr}");
        assert!(!stderr.contains("panicked"), "{stderr}");
    };
    let refused = |expected: &str| refused_with("simulation.end_time_s=0.004", expected);
    refused_with("material.sound_speed_m_s=30", "--set: material.sound_speed_m_s: cannot change when resuming");
    refused_with("inlet[0].speed_m_s=1", "--set: inlet[0].speed_m_s: cannot change when resuming");
    let checkpoint = out.join("checkpoint.bin");
    let whole = std::fs::read(&checkpoint).expect("a checkpoint");
    std::fs::write(&checkpoint, &whole[..whole.len() / 2]).expect("cut");
    refused("checkpoint.bin: (file): is damaged or cut short");
    std::fs::remove_file(&checkpoint).expect("removed");
    refused("checkpoint.bin: (file): is missing");
    std::fs::write(&checkpoint, &whole).expect("put back");
    let log = std::fs::read_to_string(out.join("run.json")).expect("log");
    std::fs::write(out.join("run.json"), log.replace("\"nu0_m2_s\": 0.05", "\"nu0_m2_s\": 0.06")).expect("edited");
    refused("checkpoint.bin: (file): was taken from another scene than the one");
    std::fs::write(out.join("run.json"), &log).expect("put back");
    let resumed = common::coil(&["resume", out.to_str().expect("utf-8"), "--quiet", "--set", "simulation.end_time_s=0.004"]);
    assert!(resumed.status.success(), "the folder resumes once whole: {}", String::from_utf8_lossy(&resumed.stderr));
    let empty = dir.join("empty");
    std::fs::create_dir_all(&empty).expect("empty folder");
    let r = common::coil(&["resume", empty.to_str().expect("utf-8")]);
    let stderr = String::from_utf8_lossy(&r.stderr);
    assert!(r.status.code() == Some(2) && stderr.contains("is not the output folder of a coil run"), "{stderr}");
    std::fs::remove_dir_all(&dir).ok();
}

/// Runs `scene` into `out` on the CPU, raising its stop flag (as Ctrl-C does) once `frame` is
/// written there, and returns how the run ended.
fn run_stopped_at(
    scene: &coil::scene::Scene,
    out: &std::path::Path,
    frame: &str,
) -> Result<coil::run::Summary, coil::run::RunError> {
    use std::sync::atomic::{AtomicBool, Ordering};
    let stop: &'static AtomicBool = Box::leak(Box::new(AtomicBool::new(false)));
    let watched = out.join(frame);
    let watcher = std::thread::spawn(move || {
        let started = std::time::Instant::now();
        while !watched.is_file() && started.elapsed() < std::time::Duration::from_secs(120) {
            std::thread::sleep(std::time::Duration::from_millis(1));
        }
        stop.store(true, Ordering::Relaxed);
    });
    let options = coil::run::RunOptions { stop: Some(stop), ..common::quiet_run_options(out) };
    let ended = coil::run::run_on(None, scene, "jet.toml", &options);
    watcher.join().expect("watcher");
    ended
}

/// A jet stopped mid-run by its program (the stop flag `coil run` sets on Ctrl-C) resumes to
/// the frames of a run never stopped: the inlets' layers and wobble, the ids and the capacity's
/// clock carry on from the checkpoint. The capacity fills during the run, so the stop must also
/// carry the time it filled. With density from the continuity equation the checkpoint carries
/// each particle's density too; particle shifting, run with it, keeps no state between steps.
/// With implicit viscosity it carries the warm start of the next solve, and with solved pressure
/// the stiffness sums.
#[test]
fn a_jet_stopped_by_its_program_resumes_where_it_was() {
    use coil::scene::DensityEquation::{Continuity, Summation};
    let cases = [
        (Summation, 0.0, false, false),
        (Continuity, 2.0, false, false),
        (Continuity, 0.0, true, false),
        (Continuity, 0.0, true, true),
    ];
    for (density, shifting, implicit, pressure) in cases {
        jet_stopped_by_its_program_resumes_where_it_was(density, shifting, implicit, pressure);
    }
}

fn jet_stopped_by_its_program_resumes_where_it_was(
    density: coil::scene::DensityEquation,
    shifting: f64,
    implicit: bool,
    pressure: bool,
) {
    let mut scene = common::scene(&common::jet_scene(
        r#"nozzle = { shape = "circle", radius_m = 0.004 }"#,
        "wobble_m = 0.0005\n[output]\nevery_s = 0.005",
    ));
    scene.simulation.end_time_s = 0.04;
    scene.simulation.max_fluid_particles = Some(80);
    scene.material.density_equation = density;
    scene.simulation.particle_shifting = shifting;
    if implicit {
        scene.material.viscosity.solver = coil::scene::ViscositySolver::Implicit;
        scene.material.viscosity.velocity_gradient = coil::scene::VelocityGradient::OwnDensity;
    }
    if pressure {
        scene.simulation.pressure = coil::scene::Pressure::DivergenceFree;
        scene.material.density_kernel = coil::scene::DensityKernelKind::Spiky;
        scene.material.density_diffusion = 0.0;
    }
    let dir = std::env::temp_dir().join(format!("coil-resume-jet-{density:?}-{implicit}-{pressure}-{}", std::process::id()));
    let (whole, stopped) = (dir.join("whole"), dir.join("stopped"));
    let done = coil::run::run_on(None, &scene, "jet.toml", &common::quiet_run_options(&whole)).expect("the whole run");
    let filled = done.capacity_reached.expect("the capacity fills").0;
    assert!(filled > 0.01, "the capacity fills after the stop: {done:?}");

    match run_stopped_at(&scene, &stopped, "frame_000002.vtu") {
        Err(coil::run::RunError::Interrupted(s)) => assert!(s.simulated_s < filled && s.steps < done.steps, "{s:?}"),
        other => panic!("expected the stop, got {other:?}"),
    }
    let resume =
        coil::run::ResumeOptions { backend: coil::run::Backend::Cpu, quiet: true, preview: false, set: vec![], stop: None };
    let resumed = coil::run::resume_on(None, &stopped, &resume).expect("the resumed run");
    assert_eq!((resumed.steps, resumed.frames, resumed.fluid_particles), (done.steps, done.frames, done.fluid_particles));
    assert_eq!(resumed.capacity_reached, done.capacity_reached);
    let solves = |s: &coil::run::Summary| [s.implicit_viscosity, s.divergence_solve, s.density_solve];
    assert_eq!(solves(&resumed), solves(&done), "the solves of the whole run");
    let (a, b) = (run_files(&whole), run_files(&stopped));
    assert!(a.len() == done.frames + 2 && a == b, "frames, boundary and series byte for byte");
    std::fs::remove_dir_all(&dir).ok();
}

/// The divergence-free jet (its `divergence_free` variant, 5 particles across) stopped by its
/// program once its rope has reached the plate, then resumed: the summary's iterations of the
/// viscosity, divergence and density solves are those of the whole run, as from one never
/// stopped. They vary from step to step, so a summary counting only the resumed steps differs.
#[test]
fn a_resumed_run_reports_the_solves_of_the_whole_run() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/newtonian_jet.toml");
    let shipped = coil::scene::Scene::load(&path).expect("the newtonian jet");
    let variant = shipped.variants.iter().find(|v| v.name == "divergence_free").expect("its divergence_free variant");
    let overrides: Vec<_> = variant
        .set
        .iter()
        .map(String::as_str)
        .chain(["simulation.end_time_s=0.3", "output.every_s=0.05"])
        .map(|o| coil::scene::overrides::Override::parse(o).expect("an override"))
        .collect();
    let scene = coil::scene::Scene::load_with(&path, &overrides).expect("the variant");
    let dir = std::env::temp_dir().join(format!("coil-resume-solves-{}", std::process::id()));
    let (whole, stopped) = (dir.join("whole"), dir.join("stopped"));
    let done = coil::run::run_on(None, &scene, "jet.toml", &common::quiet_run_options(&whole)).expect("the whole run");

    let at_stop = match run_stopped_at(&scene, &stopped, "frame_000004.vtu") {
        Err(coil::run::RunError::Interrupted(s)) => *s,
        other => panic!("expected the stop, got {other:?}"),
    };
    let resume =
        coil::run::ResumeOptions { backend: coil::run::Backend::Cpu, quiet: true, preview: false, set: vec![], stop: None };
    let resumed = coil::run::resume_on(None, &stopped, &resume).expect("the resumed run");
    let solves = |s: &coil::run::Summary| [s.implicit_viscosity, s.divergence_solve, s.density_solve];
    let mean = |s: &coil::run::Summary| solves(s).map(|s| s.expect("solved").mean_iterations);
    assert_ne!(mean(&at_stop), mean(&done), "the iterations vary, so the test can tell the whole run from its end");
    assert_eq!(solves(&resumed), solves(&done), "the solves of the whole run");
    assert_eq!(resumed.steps, done.steps);
    std::fs::remove_dir_all(&dir).ok();
}

/// A run stopped by the guard resumes from its last frame with a dt within the Eq. (10) bound
/// and finishes, its earlier frames untouched.
#[test]
fn an_unstable_run_resumes_from_its_last_frame_with_a_smaller_dt() {
    let dir = std::env::temp_dir().join(format!("coil-resume-unstable-{}", std::process::id()));
    // 15 times the bound (2e-4 s): the guard stops it at t = 0.06 s, before the frame there.
    let r = common::coil(&dam_break_run(
        &dir,
        &[
            "simulation.time_step.fixed_s=0.003",
            "simulation.time_step.allow_above_stability_bound=true",
            "output.every_s=0.02",
            "simulation.end_time_s=0.1",
        ],
    ));
    let stderr = String::from_utf8_lossy(&r.stderr);
    assert_eq!(r.status.code(), Some(3), "{stderr}");
    assert!(stderr.contains("--set simulation.time_step.fixed_s=2.000e-4` continues it"), "the bound: {stderr}");
    assert!(stderr.contains("--set simulation.time_step.viscous_velocity=half_step` continues it at the same dt"), "{stderr}");
    let before = run_files(&dir);
    assert_eq!(before.iter().filter(|f| f.0.starts_with("frame_")).count(), 3, "frames at 0, 0.02, 0.04 s");
    let again = common::coil(&["resume", dir.to_str().expect("utf-8"), "--quiet"]);
    assert_eq!(again.status.code(), Some(3), "the same dt fails again: {}", String::from_utf8_lossy(&again.stderr));
    let r = common::coil(&["resume", dir.to_str().expect("utf-8"), "--quiet", "--set", "simulation.time_step.fixed_s=0.0002"]);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let log = run_log(&dir);
    assert_eq!((log["status"].as_str(), log["summary"]["frames"].as_u64()), (Some("completed"), Some(6)), "{log}");
    let after = run_files(&dir);
    for (name, bytes) in before.iter().filter(|f| f.0.starts_with("frame_")) {
        assert!(after.iter().any(|(n, b)| n == name && b == bytes), "{name} rewritten");
    }
    std::fs::remove_dir_all(&dir).ok();
}
