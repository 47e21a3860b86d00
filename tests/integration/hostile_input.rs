//! Input as a hostile but fair user gives it: every value is bounded and means something, and
//! nothing crashes, hangs, writes a non-finite frame or writes outside the output folder.

use crate::common;

use coil::cpu::simulation::CpuSimulation;
use coil::run::RunError;
use coil::scene::particle_limit::ParticleLimit;
use coil::scene::setup::{initial_particles, initial_particles_within};
use coil::scene::{Nozzle, Scene, SceneError};
use coil_kernels::velocity_gradient::KernelSum;
use common::{coil, quiet_run_options, set};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

fn shipped(name: &str) -> String {
    std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes").join(name)).expect("a shipped scene")
}

/// A temporary folder of this test process.
fn temp(name: &str) -> PathBuf {
    std::env::temp_dir().join(format!("coil-hostile-{name}-{}", std::process::id()))
}

/// The error of `text` with `overrides`, refused at load.
fn refused(text: &str, overrides: &[&str]) -> SceneError {
    Scene::parse(&set(text, overrides), "s.toml").map(|_| ()).expect_err(&format!("{overrides:?} was accepted"))
}

/// The error of `scene`, valid at load, refused when its particles are made.
fn refused_at_setup(scene: &Scene) -> SceneError {
    initial_particles(scene, "s.toml").map(|_| ()).expect_err("the scene's particles were made")
}

/// Each `(override, field, words)` is refused at load, naming `field`, with `words` in the reason
/// and every number printed short.
fn each_refused(text: &str, cases: &[(&str, &str, &str)]) {
    for &(o, field, words) in cases {
        let e = refused(text, &[o]);
        assert!(e.file == "s.toml" && e.field == field && e.reason.contains(words), "{o}: {e}");
        assert!(!e.reason.contains("0000000000"), "{o}: a number printed long: {e}");
    }
}

/// A run's length is bounded before anything is allocated: an end time that would take more
/// steps than a machine can make (the round jet's dt is 8e-6 s), or more frames than may be
/// written, is refused naming the field, as are two frame intervals at once.
#[test]
fn runs_too_long_and_frames_too_many_are_refused_before_anything_is_allocated() {
    let jet = shipped("round_jet.toml");
    each_refused(
        &jet,
        &[
            ("simulation.end_time_s=1e9", "simulation.end_time_s", "steps"),
            ("output.every_s=1e-12", "output.every_s", "frames"),
            ("output.every_s=1e-18", "output.every_s", "frames"),
            ("simulation.time_step.fixed_s=1e-30", "simulation.time_step.fixed_s", "steps"),
            ("simulation.time_step.safety_factor=1e-300", "simulation.time_step.safety_factor", "steps"),
        ],
    );
    // A file may give one frame interval; a --set of the other replaces it.
    let both = jet.replace("every_s = 0.02", "every_s = 0.02\nevery_steps = 5");
    let e = Scene::parse(&both, "s.toml").map(|_| ()).expect_err("two frame intervals");
    assert!(e.field == "output.every_steps" && e.reason.contains("keep one of them"), "{e}");
    let by_steps = Scene::parse(&set(&jet, &["output.every_steps=5"]), "s.toml").expect("every_steps replaces every_s");
    assert_eq!((by_steps.output.every_s, by_steps.output.every_steps), (None, Some(5)));
    let out = temp("long");
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/round_jet.toml");
    let started = Instant::now();
    let r = coil(&[
        "run",
        scene.to_str().expect("utf-8"),
        "--quiet",
        "--out",
        out.to_str().expect("utf-8"),
        "--set",
        "simulation.end_time_s=1e9",
    ]);
    let stderr = String::from_utf8_lossy(&r.stderr);
    assert_eq!(r.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("simulation.end_time_s") && !stderr.contains("panicked"), "{stderr}");
    assert!(started.elapsed() < Duration::from_secs(30), "refused only after {:?}", started.elapsed());
    assert!(!out.exists(), "a refused scene created its output folder");
}

/// Numbers that no run can make sense of are refused naming their field: not finite, or out of
/// the range where the physics holds and f32 arithmetic stays finite.
#[test]
fn numbers_without_meaning_are_refused_naming_the_field() {
    let jet = shipped("round_jet.toml");
    each_refused(
        &jet,
        &[
            ("material.particle_spacing_m=1e308", "material.particle_spacing_m", "support radius"),
            ("material.particle_spacing_m=1e-5", "material.particle_spacing_m", "f32"),
            ("material.viscosity.nu0_m2_s=1e308", "material.viscosity.nu0_m2_s", "1e308"),
            ("material.sound_speed_m_s=1e30", "material.sound_speed_m_s", "1e30"),
            ("material.rest_density_kg_m3=1e308", "material.rest_density_kg_m3", "kg/m^3"),
            ("material.rest_density_kg_m3=1e-308", "material.rest_density_kg_m3", "kg/m^3"),
            ("material.viscosity.cross_k_s=1e300", "material.viscosity.cross_k_s", "1e300"),
            ("material.viscosity.cross_n=1e9", "material.viscosity.cross_n", "at most"),
            ("material.gravity_m_s2=[0.0, -1e308, 0.0]", "material.gravity_m_s2", "beyond any liquid"),
            ("inlet[0].speed_m_s=1e308", "inlet[0].speed_m_s", "at most"),
            ("inlet[0].start_s=nan", "inlet[0].start_s", "finite"),
            ("inlet[0].start_s=0.9", "inlet[0].start_s", "before simulation.end_time_s"),
            ("inlet[0].stop_s=-1.0", "inlet[0].stop_s", "after start_s"),
            ("inlet[0].motion={ velocity_m_s = [nan, 0.0, 0.0] }", "inlet[0].motion.velocity_m_s", "finite"),
            ("inlet[0].motion={ velocity_m_s = [1e308, 0.0, 0.0] }", "inlet[0].motion.velocity_m_s", "beyond any liquid"),
            ("material.gravity_m_s2=[0.0, -9.8, 0.0, 0.0]", "material.gravity_m_s2", "must have 3 elements, got 4"),
            ("inlet[0].position_m=[0.0, 0.2, 0.0, 0.0, 0.0]", "inlet[0].position_m", "must have 3 elements, got 5"),
            ("domain.max_m=[0.07, 0.23]", "domain.max_m", "length 2, expected an array of length 3"),
        ],
    );
    let dam = shipped("dam_break.toml");
    each_refused(
        &dam,
        &[
            ("fluid_block[0].velocity_m_s=[nan, 0.0, 0.0]", "fluid_block[0].velocity_m_s", "finite"),
            ("fluid_block[0].velocity_m_s=[1e308, 0.0, 0.0]", "fluid_block[0].velocity_m_s", "beyond any liquid"),
        ],
    );
    // A missing field is named itself, not the table that lacks it.
    let without: String = jet.lines().filter(|l| !l.starts_with("end_time_s")).collect::<Vec<_>>().join("\n");
    let e = Scene::parse(&without, "s.toml").map(|_| ()).expect_err("no end time");
    assert!(e.field == "simulation.end_time_s" && e.reason.contains("missing field"), "{e}");
    // A number TOML cannot hold is named as such, not taken for a string.
    for value in ["1e400", "18446744073709551616"] {
        let e = coil::scene::overrides::Override::parse(&format!("simulation.end_time_s={value}")).expect_err(value);
        assert!(e.reason.contains("out of range"), "{value}: {e}");
    }
    // f32 holds the kernels of h = 2e-5 m no longer; f64 does, and a run asked for in f32 is
    // refused though the file says f64.
    let fine = set(&jet, &["material.particle_spacing_m=1e-5", "simulation.precision=\"f64\""]);
    match Scene::parse(&fine, "s.toml") {
        Err(e) => assert!(e.field != "material.particle_spacing_m", "refused in f64: {e}"),
        Ok(scene) => {
            let e = scene.check_precision(coil::scene::Precision::F32, "s.toml").expect_err("h = 2e-5 m in f32");
            assert!(e.field == "material.particle_spacing_m" && e.reason.contains("f32"), "{e}");
        }
    }
}

/// The scene's name becomes the output folder and the series' file: only a plain file name is
/// accepted, and a refused scene writes nothing, inside the output folder or out of it.
#[test]
fn a_name_that_is_a_path_is_refused_and_nothing_is_written_outside_the_output_folder() {
    let dam = shipped("dam_break.toml");
    for name in ["/tmp/coil-escape", "../../coil-escape", "", ".hidden", "a/b", "a\\\\b"] {
        let e = refused(&dam, &[&format!("name=\"{name}\"")]);
        assert!(e.field == "name" && e.reason.contains("plain file name"), "{name:?}: {e}");
    }
    let dir = temp("name");
    std::fs::create_dir_all(&dir).expect("temp dir");
    let scene = dir.join("escape.toml");
    std::fs::write(&scene, set(&dam, &["name=\"../../escape\""])).expect("write");
    let r = coil(&["run", scene.to_str().expect("utf-8"), "--quiet", "--out", dir.join("out").to_str().expect("utf-8")]);
    assert_eq!(r.status.code(), Some(2), "{}", String::from_utf8_lossy(&r.stderr));
    let entries: Vec<_> = std::fs::read_dir(&dir).expect("dir").map(|e| e.expect("entry").file_name()).collect();
    assert_eq!(entries, vec![std::ffi::OsString::from("escape.toml")], "the refused run wrote {entries:?}");
    std::fs::remove_dir_all(&dir).ok();
}

/// Scenes valid field by field that cannot do what they seem to ask are refused when their
/// particles are made, naming what is wrong.
#[test]
fn scenes_that_cannot_do_what_they_ask_are_refused() {
    let dam = Scene::parse(&shipped("dam_break.toml"), "s.toml").expect("the dam break");
    let jet = Scene::parse(&shipped("round_jet.toml"), "s.toml").expect("the round jet");
    let torus = Scene::parse(&shipped("torus.toml"), "s.toml").expect("the torus");
    let expect = |scene: &Scene, field: &str, words: &str| {
        let e = refused_at_setup(scene);
        assert!(e.field == field && e.reason.contains(words), "expected {field}: {words}, got {e}");
    };
    let mut empty = dam.clone();
    empty.fluid_blocks.clear();
    expect(&empty, "(scene)", "has no fluid");

    let mut no_room = jet.clone();
    no_room.simulation.max_fluid_particles = Some(0);
    expect(&no_room, "simulation.max_fluid_particles", "inject nothing");

    let mut twice = dam.clone();
    twice.fluid_blocks.push(twice.fluid_blocks[0]);
    expect(&twice, "fluid_block[1]", "overlaps the fluid of an earlier shape");

    let mut two_plates = jet.clone();
    two_plates.boundaries.push(two_plates.boundaries[0]);
    expect(&two_plates, "boundary[1]", "overlap an earlier boundary");

    // The torus's tube (r = 0.08 m) centred on the plate's top surface.
    let mut through = torus.clone();
    through.fluid_tori[0].centre_m[1] = 0.0;
    expect(&through, "fluid_torus[0]", "wall");

    let mut wide = jet.clone();
    if let coil::scene::Nozzle::Circle { radius_m } = &mut wide.inlets[0].nozzle {
        *radius_m = 0.1;
    }
    expect(&wide, "inlet[0]", "outside the domain box");

    // The exit a spacing below the plate's surface, in its walls.
    let mut in_plate = jet.clone();
    in_plate.inlets[0].position_m = [0.0, -0.004, 0.0];
    expect(&in_plate, "inlet[0]", "walls of boundary[0]");
}

/// `coil check` says when the fluid capacity stops the inlets, and what the end time needs; it
/// takes only the calibration it is given, and refuses one that is not a time.
#[test]
fn check_warns_of_a_capacity_that_stalls_the_inlets_and_refuses_a_calibration_that_is_not_a_time() {
    let jet = Scene::parse(&set(&shipped("round_jet.toml"), &["simulation.max_fluid_particles=1000"]), "s.toml")
        .expect("a smaller capacity");
    let report = coil::check::check(&jet, "s.toml", None, Duration::ZERO).expect("checked");
    let (t, needed) = report.capacity_full.expect("1000 particles fill before 0.8 s");
    assert!(t > 0.0 && t < 0.8 && needed > 1000, "{report}");
    assert!(report.to_string().contains("warning            the capacity fills"), "{report}");
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/round_jet.toml");
    for bad in ["nan", "-1", "inf", "0"] {
        let r = coil(&["check", scene.to_str().expect("utf-8"), &format!("--calibrate-s={bad}")]);
        let stderr = String::from_utf8_lossy(&r.stderr);
        assert_eq!(r.status.code(), Some(2), "{bad}: {stderr}");
        assert!(stderr.contains("--calibrate-s") && !stderr.contains("panicked"), "{bad}: {stderr}");
    }
}

/// A scene file is read up to a limit, and only a regular file is read: an endless one is
/// refused, not read until memory runs out.
#[test]
fn an_endless_or_oversized_scene_file_is_refused() {
    let r = coil(&["check", "/dev/zero"]);
    let stderr = String::from_utf8_lossy(&r.stderr);
    assert_eq!(r.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("/dev/zero") && stderr.contains("not a regular file"), "{stderr}");
    let big = temp("big.toml");
    std::fs::write(&big, vec![b'#'; 2 << 20]).expect("written");
    let r = coil(&["check", big.to_str().expect("utf-8")]);
    let stderr = String::from_utf8_lossy(&r.stderr);
    assert_eq!(r.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("big.toml") && stderr.contains("longer than 1048576 bytes"), "{stderr}");
    std::fs::remove_file(&big).ok();
}

/// Two runs never share an output folder: the second is refused while the first holds it.
#[test]
fn a_folder_in_use_by_another_run_is_refused() {
    let out = temp("lock");
    std::fs::create_dir_all(&out).expect("folder");
    let held = coil::run::folder::lock(&out).expect("lockable").expect("free");
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/dam_break.toml");
    let args = ["run", scene.to_str().expect("utf-8"), "--quiet", "--out", out.to_str().expect("utf-8")];
    let r = coil(&args);
    let stderr = String::from_utf8_lossy(&r.stderr);
    assert_eq!(r.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("in use by another coil run"), "{stderr}");
    let resumed = coil(&["resume", out.to_str().expect("utf-8")]);
    assert_eq!(resumed.status.code(), Some(2), "{}", String::from_utf8_lossy(&resumed.stderr));
    drop(held);
    std::fs::remove_dir_all(&out).ok();
}

/// `coil resume` checks the frames it keeps against their sizes and digests in the checkpoint:
/// a frame deleted, cut short or replaced is named, with the command that starts over; a run
/// killed before its first checkpoint is told the same.
#[test]
fn resume_refuses_a_run_whose_earlier_frames_were_changed() {
    let out = temp("frames");
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/dam_break.toml");
    let done = coil(&[
        "run",
        scene.to_str().expect("utf-8"),
        "--quiet",
        "--out",
        out.to_str().expect("utf-8"),
        "--set",
        "simulation.end_time_s=0.004",
        "--set",
        "output.every_s=0.002",
    ]);
    assert!(done.status.success(), "{}", String::from_utf8_lossy(&done.stderr));
    let frame = out.join("frame_000001.vtu");
    let whole = std::fs::read(&frame).expect("a frame");
    let resume = || coil(&["resume", out.to_str().expect("utf-8"), "--quiet", "--set", "simulation.end_time_s=0.006"]);
    let refused = |expected: &str| {
        let r = resume();
        let stderr = String::from_utf8_lossy(&r.stderr).into_owned();
        assert_eq!(r.status.code(), Some(2), "{stderr}");
        assert!(stderr.contains("frame_000001.vtu") && stderr.contains(expected), "{stderr}");
        assert!(stderr.contains("--overwrite"), "{stderr}");
    };
    std::fs::remove_file(&frame).expect("deleted");
    refused("cannot be read");
    std::fs::write(&frame, &whole[..whole.len() / 2]).expect("cut short");
    refused("bytes where the run wrote");
    let mut replaced = whole.clone();
    let last = replaced.len() - 30;
    replaced[last] ^= 1;
    std::fs::write(&frame, &replaced).expect("replaced");
    refused("was changed");
    std::fs::write(&frame, &whole).expect("put back");
    let r = resume();
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    std::fs::remove_file(out.join("checkpoint.bin")).expect("as if killed before its first checkpoint");
    let r = resume();
    let stderr = String::from_utf8_lossy(&r.stderr);
    assert!(r.status.code() == Some(2) && stderr.contains("is missing") && stderr.contains("--overwrite"), "{stderr}");
    std::fs::remove_dir_all(&out).ok();
}

/// The guard reads density as well as speed, and no frame holding a value that is not finite
/// is written: the frame refuses it as an instability, naming the field and the particle.
#[test]
fn a_non_finite_value_stops_the_run_before_a_frame_holds_it() {
    use coil::simulation::model::StressModel;
    use coil_kernels::cross_viscosity::Newtonian;
    let scene = Scene::parse(&shipped("dam_break.toml"), "s.toml").expect("the dam break");
    let initial = initial_particles(&scene, "s.toml").expect("particles");
    let mut sim = CpuSimulation::<f64, _>::new(&scene, &initial, StressModel(Newtonian { nu0: 0.05 }, KernelSum));
    sim.step().expect("a step");
    let mut frame = coil::output::frame::Frame::default();
    frame.capture(&sim.run, sim.host());
    assert!(frame.non_finite().is_none());
    frame.viscosity[3] = f32::NAN;
    frame.density[5] = f32::INFINITY;
    let (particles, first) = frame.non_finite().expect("found");
    assert_eq!(particles, 2);
    assert!(first.starts_with("viscosity of particle") && first.ends_with("NaN"), "{first}");

    use coil_kernels::diagnostics::{particle_figures, DiagnosticsArgs};
    use coil_kernels::view::{Vec3View, View};
    let fluid = sim.run.fluid;
    // A fluid particle at rest whose density is NaN.
    let (id, v, density) = ([fluid.boundary_count], [0.0f64], [f64::NAN]);
    let args = DiagnosticsArgs {
        fluid,
        runaway_speed2: 1.0,
        id: View::new(&id),
        velocity: Vec3View::new(&v, &v, &v),
        density: View::new(&density),
    };
    assert_eq!(particle_figures(0, &args).bad_particles, 1, "a NaN density passed the guard");
}

/// Mutations of a shipped scene as a user might make them.
enum Mutation {
    /// A number replaced by another.
    Number(String, String),
    /// A value replaced by one of another type.
    Type(String, String),
    /// An array one element longer or shorter.
    Length(String, bool),
    Delete(String),
    Name(String),
    /// A line of the text repeated.
    Duplicate(usize),
    /// The first variant renamed: a path, or the name of another variant.
    VariantName(String),
}

/// Every leaf of `value` as `--set` spells its key.
fn leaves(value: &toml::Value, path: String, out: &mut Vec<(String, toml::Value)>) {
    match value {
        toml::Value::Table(t) => {
            for (k, v) in t {
                leaves(v, if path.is_empty() { k.clone() } else { format!("{path}.{k}") }, out);
            }
        }
        toml::Value::Array(items) if items.iter().all(toml::Value::is_table) && !items.is_empty() => {
            for (k, v) in items.iter().enumerate() {
                leaves(v, format!("{path}[{k}]"), out);
            }
        }
        v => out.push((path, v.clone())),
    }
}

fn pick<'a, T>(items: &'a [T], state: &mut u64) -> &'a T {
    &items[(common::uniform(state) * items.len() as f64) as usize % items.len()]
}

/// A mutation of `text`; most of the time of a field under one of the `focus` prefixes, where
/// some are given.
fn mutation(text: &str, focus: &[&str], state: &mut u64) -> Mutation {
    let mut all = Vec::new();
    leaves(&toml::Value::Table(toml::from_str(text).expect("a shipped scene")), String::new(), &mut all);
    all.retain(|(k, _)| !k.starts_with("variant") && k != "notes" && k != "description");
    let focused: Vec<_> = all.iter().filter(|(k, _)| focus.iter().any(|f| k.starts_with(f))).cloned().collect();
    if !focused.is_empty() && common::uniform(state) < 0.7 {
        all = focused;
    }
    let (key, value) = pick(&all, state).clone();
    let numbers = |x: f64| {
        [
            "nan".into(),
            "inf".into(),
            "-inf".into(),
            "0.0".into(),
            format!("{:e}", -x),
            "1e308".into(),
            "-1e308".into(),
            "1e-308".into(),
            format!("{:e}", x * 1e6),
            format!("{:e}", x * 1e-6),
            format!("{:e}", x * 3.0),
            format!("{:e}", x * 0.3),
            "9223372036854775807".into(),
        ]
    };
    let names = ["../../../x", "", ".", "a/b", "/tmp/abs", "(another's)"];
    match (common::uniform(state) * 11.0) as u32 {
        10 if text.contains("[[variant]]") => Mutation::VariantName(pick(&names, state).to_string()),
        0 => Mutation::Type(key, pick(&["\"text\"", "true", "{ a = 1 }", "[]"], state).to_string()),
        1 => Mutation::Delete(key),
        2 => Mutation::Name(pick(&["\"/tmp/abs\"", "\"../../up\"", "\"\"", "\".hid\"", "\"a/b\""], state).to_string()),
        3 => Mutation::Duplicate((common::uniform(state) * text.lines().count() as f64) as usize),
        4 if value.is_array() => Mutation::Length(key, common::uniform(state) < 0.5),
        _ => match &value {
            toml::Value::Float(x) => Mutation::Number(key, pick(&numbers(*x), state).clone()),
            toml::Value::Integer(i) => Mutation::Number(key, pick(&numbers(*i as f64), state).clone()),
            toml::Value::Array(items) if !items.is_empty() => {
                let k = (common::uniform(state) * items.len() as f64) as usize % items.len();
                let x = items[k].as_float().or(items[k].as_integer().map(|i| i as f64)).unwrap_or(1.0);
                let mut items = items.clone();
                items[k] = toml::from_str::<toml::Table>(&format!("v = {}", pick(&numbers(x), state)))
                    .map(|mut t| t.remove("v").expect("v"))
                    .unwrap_or(toml::Value::Float(f64::NAN));
                Mutation::Number(key, toml::Value::Array(items).to_string())
            }
            _ => Mutation::Type(key, "1.5".into()),
        },
    }
}

/// The scene text after `m`.
fn mutated(text: &str, m: &Mutation) -> String {
    let mut table: toml::Table = toml::from_str(text).expect("a shipped scene");
    let value = |v: &str| toml::from_str::<toml::Table>(&format!("v = {v}")).expect("a value").remove("v").expect("v");
    let edit = |table: &mut toml::Table, key: &str, f: &dyn Fn(&mut toml::Table, &str)| {
        let mut t = table;
        let parts: Vec<&str> = key.split('.').collect();
        for part in &parts[..parts.len() - 1] {
            t = match part.split_once('[') {
                None => t.get_mut(*part).and_then(toml::Value::as_table_mut).expect("a table"),
                Some((name, i)) => {
                    let i: usize = i.trim_end_matches(']').parse().expect("an index");
                    t.get_mut(name).and_then(|a| a.as_array_mut()).and_then(|a| a[i].as_table_mut()).expect("an entry")
                }
            };
        }
        f(t, parts[parts.len() - 1]);
    };
    match m {
        Mutation::Number(key, v) | Mutation::Type(key, v) => edit(&mut table, key, &|t, k| {
            t.insert(k.into(), value(v));
        }),
        Mutation::Delete(key) => edit(&mut table, key, &|t, k| {
            t.remove(k);
        }),
        Mutation::Length(key, longer) => edit(&mut table, key, &|t, k| {
            let a = t.get_mut(k).and_then(toml::Value::as_array_mut).expect("an array");
            if *longer {
                let last = a.last().cloned().unwrap_or(toml::Value::Float(0.0));
                a.push(last);
            } else {
                a.pop();
            }
        }),
        Mutation::Name(name) => {
            table.insert("name".into(), value(name));
        }
        Mutation::VariantName(name) => {
            let variants = table.get_mut("variant").and_then(toml::Value::as_array_mut).expect("variants");
            let name = match name.as_str() {
                "(another's)" if variants.len() > 1 => variants[1]["name"].clone(),
                "(another's)" => variants[0]["name"].clone(),
                name => toml::Value::String(name.into()),
            };
            if variants.len() == 1 {
                variants.push(variants[0].clone());
            }
            variants[0].as_table_mut().expect("a variant").insert("name".into(), name);
        }
        Mutation::Duplicate(line) => {
            let lines: Vec<&str> = text.lines().collect();
            let mut out: Vec<&str> = lines.clone();
            out.insert(*line, lines[*line]);
            return out.join("\n");
        }
    }
    toml::to_string(&table).expect("a table serialises")
}

/// What became of a mutated scene.
enum Outcome {
    Refused(SceneError),
    /// It ran a few steps, writing these frames.
    Ran(Vec<PathBuf>),
    /// Valid, but larger than this test runs.
    TooLarge,
}

/// Loads `text` as `coil run` does, checks it, and runs a few steps of it into `out`, a frame
/// each step.
fn try_scene(text: &str, out: &Path) -> Outcome {
    let scene = match Scene::parse(text, "fuzz.toml") {
        Err(e) => return Outcome::Refused(e),
        Ok(scene) => scene,
    };
    let d = &scene.domain;
    let cells: f64 = (0..3).map(|a| ((d.max_m[a] - d.min_m[a]) / scene.support_radius()).ceil()).product();
    if cells > 2e6 {
        return Outcome::TooLarge;
    }
    let small = ParticleLimit { most: 60_000.0, why: "the fuzz test's limit".into() };
    match initial_particles_within(&scene, "fuzz.toml", &small) {
        Err(e) if e.reason.contains(&small.why) => return Outcome::TooLarge,
        Err(e) => return Outcome::Refused(e),
        Ok(_) if scene.simulation.max_fluid_particles.is_some_and(|m| m as f64 > small.most) => return Outcome::TooLarge,
        Ok(_) => {}
    }
    if let Err(e) = coil::check::check(&scene, "fuzz.toml", None, Duration::ZERO) {
        return Outcome::Refused(e);
    }
    let mut scene = scene;
    let h = scene.support_radius();
    let v = scene.material.viscosity;
    let (bound, _) = coil::time_step::StabilityBound::new(h, scene.material.sound_speed_m_s, v.nu0_m2_s.max(v.nu_inf())).dt();
    let dt = scene.simulation.time_step.fixed_s.unwrap_or(bound * scene.simulation.time_step.safety_factor);
    scene.simulation.end_time_s = scene.simulation.end_time_s.min(3.5 * dt);
    scene.output.every_s = None;
    scene.output.every_steps = Some(1);
    std::fs::remove_dir_all(out).ok();
    match coil::run::run_on(None, &scene, "fuzz.toml", &quiet_run_options(out)) {
        Ok(_) | Err(RunError::Unstable(..)) => {}
        Err(RunError::Scene(e)) => return Outcome::Refused(e),
        Err(e) => panic!("{e}"),
    }
    let mut frames: Vec<PathBuf> = std::fs::read_dir(out)
        .expect("the output folder")
        .map(|e| e.expect("entry").path())
        .filter(|p| p.extension().is_some_and(|x| x == "vtu") && p.file_name().is_some_and(|n| n != "boundary.vtu"))
        .collect();
    frames.sort();
    Outcome::Ran(frames)
}

/// Mutated shipped scenes (numbers, types, array lengths, deleted and repeated keys, names),
/// from a fixed seed: each is either refused naming a field, or checked and run for a few
/// steps writing only finite frames; none panics or takes long.
#[test]
fn mutated_scenes_are_refused_naming_a_field_or_run_writing_only_finite_frames() {
    let out = temp("fuzz");
    let mut state = 0x5eed_c011_u64;
    let mut outcomes = Outcomes::default();
    for name in ["round_jet.toml", "dam_break.toml", "torus.toml", "moving_jet.toml", "rectangular_jet.toml"] {
        let text = shipped(name);
        for _ in 0..100 {
            let m = mutation(&text, &[], &mut state);
            outcomes.try_mutated(name, &mutated(&text, &m), &out);
        }
    }
    std::fs::remove_dir_all(&out).ok();
    eprintln!("{} mutated scenes refused, {} run", outcomes.refused, outcomes.ran);
    assert!(outcomes.refused > 100 && outcomes.ran > 50, "{outcomes:?}: the mutations should reach both outcomes");
}

/// The solvers' sections written out in full at their defaults, as overrides.
const SOLVER_SECTIONS: [&str; 2] = [
    "simulation.divergence_free={ density_tolerance = 5e-4, divergence_tolerance = 1e-3, max_iterations = 100, min_iterations = 2, relaxation = 0.5, chebyshev_radius = 0.0, on_no_convergence = \"warn\", cfl_factor = 0.2, max_time_step_s = 1e-3, wall_pressure = \"once\" }",
    "material.viscosity.implicit={ tolerance = 1e-3, max_iterations = 100, on_no_convergence = \"stop\", picard_iterations = 0 }",
];

/// Every variant of every shipped scene, its solvers' sections written out in full, mutated
/// mostly in those sections, the pressure and viscosity solvers and the variants' names: each
/// is refused naming a field, or checked and run for a few steps writing only finite frames.
#[test]
fn mutated_variants_and_solver_sections_are_refused_naming_a_field_or_run_writing_only_finite_frames() {
    let out = temp("fuzz-solvers");
    let mut state = 0x5eed_d15c_u64;
    let mut outcomes = Outcomes::default();
    let focus = ["simulation.divergence_free", "material.viscosity.implicit", "simulation.pressure", "material.viscosity.solver"];
    let mut variants = 0;
    for name in
        ["round_jet.toml", "newtonian_jet.toml", "dam_break.toml", "torus.toml", "moving_jet.toml", "rectangular_jet.toml"]
    {
        let text = shipped(name);
        for variant in Scene::parse(&text, name).expect("a shipped scene").variants {
            variants += 1;
            let sets: Vec<&str> = SOLVER_SECTIONS.iter().copied().chain(variant.set.iter().map(String::as_str)).collect();
            let base = set(&text, &sets);
            for _ in 0..25 {
                let m = mutation(&base, &focus, &mut state);
                outcomes.try_mutated(&format!("{name} --variant {}", variant.name), &mutated(&base, &m), &out);
            }
        }
    }
    std::fs::remove_dir_all(&out).ok();
    eprintln!("{} mutated variants ({variants} variants) refused, {} run", outcomes.refused, outcomes.ran);
    assert!(outcomes.refused > 100 && outcomes.ran > 50, "{outcomes:?}: the mutations should reach both outcomes");
}

/// Counts of what became of mutated scenes.
#[derive(Debug, Default)]
struct Outcomes {
    refused: usize,
    ran: usize,
}

impl Outcomes {
    /// Tries the mutated scene `scene` of the shipped `name` into `out`: refused naming a field,
    /// or run writing only finite frames, without a panic and within 20 s.
    fn try_mutated(&mut self, name: &str, scene: &str, out: &Path) {
        let started = Instant::now();
        let outcome =
            std::panic::catch_unwind(|| try_scene(scene, out)).unwrap_or_else(|_| panic!("{name}: panicked on\n{scene}"));
        assert!(started.elapsed() < Duration::from_secs(20), "{name}: took {:?} on\n{scene}", started.elapsed());
        match outcome {
            Outcome::Refused(e) => {
                assert!(!e.field.is_empty() && !e.reason.is_empty(), "{name}: {e}");
                self.refused += 1;
            }
            Outcome::Ran(frames) => {
                assert!(!frames.is_empty(), "{name}: no frame written for\n{scene}");
                for frame in frames {
                    let data = coil::output::vtu_read::read_frame(&frame).expect("a whole frame");
                    let finite = data.position.iter().flatten().all(|x| x.is_finite())
                        && data.scalars.values().flatten().all(|x| x.is_finite())
                        && data.vectors.values().flatten().flatten().all(|x| x.is_finite());
                    assert!(finite, "{name}: {} holds a non-finite value; scene\n{scene}", frame.display());
                }
                self.ran += 1;
            }
            Outcome::TooLarge => {}
        }
    }
}

/// A write that fails (here a frame's temporary name taken by a folder, as a full disk would
/// fail it) ends the run with exit 1, naming the file; `run.json` logs the failure instead of
/// "running", and no temporary file is left behind.
#[test]
fn a_failed_write_is_named_and_logged_and_leaves_no_temporary() {
    let out = temp("write");
    std::fs::create_dir_all(out.join("frame_000001.vtu.tmp")).expect("a folder where the frame's temporary goes");
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/dam_break.toml");
    let r = coil(&[
        "run",
        scene.to_str().expect("utf-8"),
        "--quiet",
        "--out",
        out.to_str().expect("utf-8"),
        "--set",
        "simulation.end_time_s=0.004",
        "--set",
        "output.every_s=0.002",
    ]);
    let stderr = String::from_utf8_lossy(&r.stderr);
    assert_eq!(r.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("frame_000001.vtu") && !stderr.contains("run.json"), "{stderr}");
    let log: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("run.json")).expect("the log")).expect("whole JSON");
    assert_eq!(log["status"], "failed");
    assert!(log["diagnosis"].as_str().is_some_and(|d| d.contains("frame_000001.vtu")), "{log}");
    let temporaries: Vec<_> = std::fs::read_dir(&out)
        .expect("the folder")
        .map(|e| e.expect("entry").path())
        .filter(|p| p.is_file() && p.extension().is_some_and(|x| x == "tmp"))
        .collect();
    assert!(temporaries.is_empty(), "{temporaries:?}");
    std::fs::remove_dir_all(&out).ok();
}

/// The newtonian jet with its `divergence_free` variant applied: pressure and viscosity solved.
fn divergence_free_jet() -> String {
    let text = shipped("newtonian_jet.toml");
    let scene = Scene::parse(&text, "s.toml").expect("the newtonian jet");
    let variant = scene.variants.iter().find(|v| v.name == "divergence_free").expect("its divergence_free variant");
    set(&text, &variant.set.iter().map(String::as_str).collect::<Vec<_>>())
}

/// A run whose steps cannot reach its end time is refused at load, naming the field that makes
/// them so many: under solved pressure the step is counted at the fastest the fluid can move,
/// and every field of the solvers' sections has a range, checked whichever solver the scene
/// picks (a `--set` of the solver must not bring an unchecked value to life).
#[test]
fn solver_settings_that_cannot_progress_are_refused_naming_the_field() {
    let jet = divergence_free_jet();
    each_refused(
        &jet,
        &[
            ("simulation.divergence_free.cfl_factor=1e-12", "simulation.divergence_free.cfl_factor", "from 0.001 to 1"),
            ("simulation.divergence_free.cfl_factor=5e-324", "simulation.divergence_free.cfl_factor", "from 0.001 to 1"),
            ("simulation.divergence_free.max_time_step_s=5e-324", "simulation.divergence_free.max_time_step_s", "steps"),
            ("simulation.divergence_free.max_time_step_s=10", "simulation.divergence_free.max_time_step_s", "from 0 to 1"),
            ("simulation.divergence_free.relaxation=5e-324", "simulation.divergence_free.relaxation", "from 0.01 to 0.75"),
            ("simulation.divergence_free.density_tolerance=1e-30", "simulation.divergence_free.density_tolerance", "fraction"),
            ("simulation.divergence_free.min_iterations=101", "simulation.divergence_free.min_iterations", "at most"),
            ("material.viscosity.implicit.tolerance=1e-30", "material.viscosity.implicit.tolerance", "below 1"),
            ("material.viscosity.implicit.max_iterations=0", "material.viscosity.implicit.max_iterations", "from 1"),
            ("material.viscosity.implicit.picard_iterations=1000", "material.viscosity.implicit.picard_iterations", "from 0"),
        ],
    );
    // At the slowest CFL factor the jet's fall (about 2.6 m/s) takes 6e9 steps to 1e4 s.
    let e = refused(&jet, &["simulation.divergence_free.cfl_factor=1e-3", "simulation.end_time_s=1e4", "output.every_s=100"]);
    assert!(e.field == "simulation.divergence_free.cfl_factor" && e.reason.contains("steps"), "{e}");
    // The weakly compressible, explicit round jet: its solver sections are unread, and checked.
    let round = shipped("round_jet.toml");
    each_refused(
        &round,
        &[
            ("material.viscosity.implicit={ tolerance = -1 }", "material.viscosity.implicit.tolerance", "below 1"),
            ("simulation.divergence_free={ relaxation = 2.0 }", "simulation.divergence_free.relaxation", "0.75"),
        ],
    );
    let r = coil(&[
        "check",
        "scenes/newtonian_jet.toml",
        "--variant",
        "divergence_free",
        "--set",
        "simulation.divergence_free.cfl_factor=1e-12",
    ]);
    let stderr = String::from_utf8_lossy(&r.stderr);
    assert!(r.status.code() == Some(2) && stderr.contains("simulation.divergence_free.cfl_factor"), "{stderr}");
}

/// Two inlets that lay their particles on top of each other are refused, naming the later one;
/// two side by side are not.
#[test]
fn two_inlets_at_the_same_place_are_refused() {
    let mut scene = Scene::parse(&shipped("round_jet.toml"), "s.toml").expect("the round jet");
    scene.inlets.push(scene.inlets[0].clone());
    let text = toml::to_string(&scene).expect("serialises");
    let e = Scene::parse(&text, "s.toml").map(|_| ()).expect_err("two identical inlets");
    assert!(e.field == "inlet[1]" && e.reason.contains("overlaps that of inlet[0]"), "{e}");
    // One that starts when the other stops takes turns with it.
    scene.inlets[0].stop_s = Some(0.2);
    scene.inlets[1].start_s = 0.2;
    Scene::parse(&toml::to_string(&scene).expect("serialises"), "s.toml").expect("inlets that take turns");
    // Side by side, a diameter and a spacing apart.
    let Nozzle::Circle { radius_m } = scene.inlets[0].nozzle else { panic!("a round nozzle") };
    scene.inlets[1].start_s = 0.0;
    scene.inlets[0].stop_s = None;
    scene.inlets[1].position_m[0] += 2.0 * radius_m + scene.material.particle_spacing_m;
    scene.domain.min_m[0] -= 0.1;
    scene.domain.max_m[0] += 0.1;
    Scene::parse(&toml::to_string(&scene).expect("serialises"), "s.toml").expect("inlets side by side");
}

/// `--threads` beyond a few a core is refused at once by every command that takes it, before
/// a thread is spawned.
#[test]
fn thread_counts_beyond_the_machine_are_refused_by_every_command() {
    let out = temp("threads");
    std::fs::create_dir_all(&out).expect("folder");
    let dir = out.to_str().expect("utf-8");
    let commands: [&[&str]; 7] = [
        &["run", "scenes/dam_break.toml", "--out", dir],
        &["check", "scenes/dam_break.toml"],
        &["resume", dir],
        &["render", dir],
        &["surface", dir],
        &["pov", dir],
        &["bench", "--out", dir],
    ];
    for command in commands {
        for threads in ["100000", "0"] {
            let started = Instant::now();
            let r = coil(&[command, &["--threads", threads]].concat());
            let stderr = String::from_utf8_lossy(&r.stderr);
            assert_eq!(r.status.code(), Some(2), "{command:?} --threads {threads}: {stderr}");
            assert!(stderr.contains("--threads: must be from 1 to"), "{command:?}: {stderr}");
            assert!(started.elapsed() < Duration::from_secs(10), "{command:?}: refused only after {:?}", started.elapsed());
        }
    }
    std::fs::remove_dir_all(&out).ok();
}

/// A variant's name joins the output folder's, so it is a plain file name, and names one
/// variant only; `--set` cannot edit the variants it would never see.
#[test]
fn a_variant_name_that_is_a_path_is_refused_and_nothing_is_written_outside_the_output_folder() {
    let jet = shipped("round_jet.toml");
    let parsed = Scene::parse(&jet, "s.toml").expect("the round jet");
    let with_variants = |edit: &dyn Fn(&mut Vec<coil::scene::Variant>)| {
        let mut scene = parsed.clone();
        edit(&mut scene.variants);
        Scene::parse(&toml::to_string(&scene).expect("serialises"), "s.toml").map(|_| ()).expect_err("refused")
    };
    for name in ["../../../x", "", ".", "a/b", "/tmp/coil-variant"] {
        let e = with_variants(&|v| v[0].name = name.into());
        assert!(e.field == "variant[0].name" && e.reason.contains("plain file name"), "{name:?}: {e}");
    }
    let e = with_variants(&|v| v[0].name = v[1].name.clone());
    assert!(e.field == "variant[1].name" && e.reason.contains("is the name of variant[0] too"), "{e}");
    let e = with_variants(&|v| v[0].set = vec!["no equals sign".into()]);
    assert!(e.field == "variant[0].set" && e.reason.contains("key=value"), "{e}");

    let dir = temp("variant");
    let deep = dir.join("a/b/c");
    std::fs::create_dir_all(&deep).expect("folders");
    let scene = dir.join("escape.toml");
    std::fs::write(&scene, jet.replace("name = \"paper\"", "name = \"../../../x\"")).expect("write");
    let r = std::process::Command::new(env!("CARGO_BIN_EXE_coil"))
        .args(["run", scene.to_str().expect("utf-8"), "--quiet", "--variant", "../../../x"])
        .current_dir(&deep)
        .output()
        .expect("coil runs");
    let stderr = String::from_utf8_lossy(&r.stderr);
    assert!(r.status.code() == Some(2) && stderr.contains("variant[1].name"), "{stderr}");
    let entries: Vec<_> = std::fs::read_dir(&dir).expect("dir").map(|e| e.expect("entry").file_name()).collect();
    assert_eq!(entries.len(), 2, "the refused run wrote {entries:?}");
    assert!(std::fs::read_dir(&deep).expect("dir").next().is_none(), "the refused run wrote into its working folder");

    let r = coil(&["run", "scenes/round_jet.toml", "--variant", "paper", "--set", "variant[1].set=[]"]);
    let stderr = String::from_utf8_lossy(&r.stderr);
    assert!(r.status.code() == Some(2) && stderr.contains("--variant NAME applies before any --set"), "{stderr}");
    std::fs::remove_dir_all(&dir).ok();
}

/// A short round jet into `out`: three frames, the last of 105 particles.
fn short_jet_run(out: &Path) {
    std::fs::remove_dir_all(out).ok();
    let r = coil(&[
        "run",
        "scenes/round_jet.toml",
        "--quiet",
        "--out",
        out.to_str().expect("utf-8"),
        "--set",
        "simulation.end_time_s=0.02",
        "--set",
        "output.every_s=0.01",
    ]);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
}

/// Each command that reads a run's frames, with its arguments for the run in `dir`.
fn frame_readers(dir: &Path) -> Vec<Vec<String>> {
    let d = dir.to_str().expect("utf-8").to_string();
    let frame = dir.join("frame_000002.vtu").to_str().expect("utf-8").to_string();
    [
        vec!["render", d.as_str(), "--quiet"],
        vec!["surface", d.as_str(), "--quiet"],
        vec!["pov", d.as_str()],
        vec!["axis", d.as_str()],
        vec!["preview", frame.as_str()],
    ]
    .iter()
    .map(|args| args.iter().map(|a| a.to_string()).collect())
    .collect()
}

/// Every reader of frames refuses `dir`'s damaged last frame with exit 2 within a few seconds,
/// naming the file and `words`, never panicking.
fn every_reader_refuses(dir: &Path, words: &str) {
    for args in frame_readers(dir) {
        let started = Instant::now();
        let r = coil(&args);
        let stderr = String::from_utf8_lossy(&r.stderr);
        assert_eq!(r.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(stderr.contains("frame_000002.vtu") && stderr.contains(words), "{args:?}: expected {words:?} in {stderr}");
        assert!(!stderr.contains("panicked"), "{args:?}: {stderr}");
        assert!(started.elapsed() < Duration::from_secs(10), "{args:?}: refused only after {:?}", started.elapsed());
    }
}

/// `bytes` of a raw `.vtu` frame with the first coordinate of particle `k` set to `x`.
fn with_position(bytes: &[u8], k: usize, x: f64) -> Vec<u8> {
    let text = String::from_utf8_lossy(bytes);
    let tag = text.find("Name=\"position\"").expect("a position array");
    let offset_at = tag + text[tag..].find("offset=\"").expect("its offset") + 8;
    let offset: usize = text[offset_at..offset_at + text[offset_at..].find('"').expect("a quote")].parse().expect("a number");
    let data = text.find("<AppendedData encoding=\"raw\">").expect("raw data");
    let start = data + text[data..].find('_').expect("its start") + 1 + offset + 8 + 24 * k;
    let mut out = bytes.to_vec();
    out[start..start + 8].copy_from_slice(&x.to_le_bytes());
    out
}

/// A frame is input like any other: one with a position that is not finite or lies a long way
/// outside the run's domain, or that claims more particles than its bytes hold, is refused by
/// every command that reads frames, naming the file and the particle.
#[test]
fn a_bad_frame_is_refused_by_every_reader_naming_the_file_and_the_particle() {
    let dir = temp("bad-frame");
    short_jet_run(&dir);
    let frame = dir.join("frame_000002.vtu");
    let whole = std::fs::read(&frame).expect("a frame");
    std::fs::write(&frame, with_position(&whole, 7, f64::NAN)).expect("written");
    every_reader_refuses(&dir, "the position of particle 7 (id");
    std::fs::write(&frame, with_position(&whole, 7, 1e6)).expect("written");
    every_reader_refuses(&dir, "particle 7 (id");
    let text = String::from_utf8_lossy(&whole).replace("NumberOfPoints=\"105\"", "NumberOfPoints=\"100000000000000\"");
    std::fs::write(&frame, text.as_bytes()).expect("written");
    every_reader_refuses(&dir, "claims 100000000000000 points");
    std::fs::write(&frame, &whole).expect("put back");
    for args in frame_readers(&dir) {
        let r = coil(&args);
        assert!(r.status.success(), "{args:?} on the whole frame: {}", String::from_utf8_lossy(&r.stderr));
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// Only regular files are read: a frame that is a link to `/dev/zero` (endless) or a FIFO
/// (which blocks whoever opens it to read) is refused at once by every reader, as are a run's
/// log and checkpoint and a scene file.
#[cfg(unix)]
#[test]
fn files_that_are_not_regular_are_refused_without_reading_them() {
    let dir = temp("not-regular");
    short_jet_run(&dir);
    let frame = dir.join("frame_000002.vtu");
    let fifo = |path: &Path| {
        std::fs::remove_file(path).ok();
        let made = std::process::Command::new("mkfifo").arg(path).status().expect("mkfifo runs");
        assert!(made.success(), "mkfifo {}", path.display());
    };
    let zero = |path: &Path| {
        std::fs::remove_file(path).ok();
        std::os::unix::fs::symlink("/dev/zero", path).expect("a link");
    };
    for make in [&zero as &dyn Fn(&Path), &fifo] {
        make(&frame);
        every_reader_refuses(&dir, "not a regular file");
    }
    let checkpoint = dir.join("checkpoint.bin");
    for make in [&zero as &dyn Fn(&Path), &fifo] {
        make(&checkpoint);
        let r = coil(&["resume", dir.to_str().expect("utf-8"), "--quiet", "--set", "simulation.end_time_s=0.03"]);
        let stderr = String::from_utf8_lossy(&r.stderr);
        assert!(
            r.status.code() == Some(2) && stderr.contains("checkpoint.bin") && stderr.contains("not a regular file"),
            "{stderr}"
        );
    }
    let log = dir.join("run.json");
    fifo(&log);
    let r = coil(&["axis", dir.to_str().expect("utf-8")]);
    let stderr = String::from_utf8_lossy(&r.stderr);
    assert!(r.status.code() == Some(2) && stderr.contains("run.json") && stderr.contains("not a regular file"), "{stderr}");
    let scene = dir.join("scene.toml");
    fifo(&scene);
    let r = coil(&["check", scene.to_str().expect("utf-8")]);
    let stderr = String::from_utf8_lossy(&r.stderr);
    assert!(r.status.code() == Some(2) && stderr.contains("scene.toml") && stderr.contains("not a regular file"), "{stderr}");
    std::fs::remove_dir_all(&dir).ok();
}

/// The numerical controls of the solvers may be retuned on resume (to get an unconverged solve
/// past a hard stretch), and `run.json` logs the change; what a wall pushes with is physics,
/// and is refused.
#[test]
fn resume_retunes_the_solvers_and_logs_it_but_keeps_their_physics() {
    let out = temp("retune");
    let r = common::run_divergence_free_jet(&out, &["simulation.end_time_s=0.02", "output.every_s=0.01"]);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let dir = out.to_str().expect("utf-8");
    let r = coil(&[
        "resume",
        dir,
        "--quiet",
        "--set",
        "simulation.divergence_free.wall_pressure=mirrored",
        "--set",
        "simulation.end_time_s=0.03",
    ]);
    let stderr = String::from_utf8_lossy(&r.stderr);
    assert!(r.status.code() == Some(2) && stderr.contains("simulation.divergence_free.wall_pressure: cannot change"), "{stderr}");
    let r = coil(&[
        "resume",
        dir,
        "--quiet",
        "--set",
        "simulation.divergence_free.density_tolerance=1e-4",
        "--set",
        "material.viscosity.implicit.tolerance=1e-2",
        "--set",
        "simulation.end_time_s=0.03",
    ]);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let log: serde_json::Value = serde_json::from_slice(&std::fs::read(out.join("run.json")).expect("the log")).expect("JSON");
    assert_eq!(log["scene"]["simulation"]["divergence_free"]["density_tolerance"], 1e-4, "{log}");
    assert_eq!(log["scene"]["material"]["viscosity"]["implicit"]["tolerance"], 1e-2, "{log}");
    let overrides: Vec<&str> = log["overrides"].as_array().expect("overrides").iter().filter_map(|o| o.as_str()).collect();
    assert!(overrides.contains(&"simulation.divergence_free.density_tolerance=1e-4"), "{overrides:?}");
    assert_eq!(log["summary"]["density_solve"]["tolerance"], 1e-4, "{log}");
    std::fs::remove_dir_all(&out).ok();
}
