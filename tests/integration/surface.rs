//! The free surface: meshes of a frame's fluid, and the pictures and movie drawn from them.

use coil::output::render::{Camera, Stage};
use coil::output::surface::{reconstruct, Fluid, SurfaceMesh, SurfaceParameters};
use coil::output::vtu_read::FrameData;
use std::collections::{BTreeMap, HashMap};

use crate::common;

const SPACING: f64 = 0.004;
/// The ball's radius in spacings.
const RADIUS: f64 = 8.0;
const CENTRE: [f64; 3] = [0.01, 0.05, -0.02];

/// Particles on the lattice within RADIUS spacings of CENTRE, at rest density, their viscosity
/// rising with height.
fn ball() -> FrameData {
    let r = RADIUS as i64;
    let mut position = Vec::new();
    for i in -r..=r {
        for j in -r..=r {
            for k in -r..=r {
                if ((i * i + j * j + k * k) as f64) <= RADIUS * RADIUS {
                    position.push([
                        CENTRE[0] + i as f64 * SPACING,
                        CENTRE[1] + j as f64 * SPACING,
                        CENTRE[2] + k as f64 * SPACING,
                    ]);
                }
            }
        }
    }
    let n = position.len();
    let viscosity = position.iter().map(|p| (0.05 + (p[1] - CENTRE[1])) as f32).collect();
    let scalars = BTreeMap::from([("density".to_string(), vec![1000.0; n]), ("viscosity".to_string(), viscosity)]);
    let vectors = BTreeMap::from([("velocity".to_string(), vec![[0.0, -0.3, 0.4]; n])]);
    FrameData { position, scalars, vectors, id: (0..n as u32).collect() }
}

fn mesh_of_ball() -> SurfaceMesh {
    let parameters = SurfaceParameters::for_run(SPACING, 2.0 * SPACING, 1000.0);
    let frame = ball();
    reconstruct(Fluid::of(&frame).expect("a fluid"), &parameters).expect("a surface")
}

fn from_centre(v: [f32; 3]) -> [f64; 3] {
    [0, 1, 2].map(|a| f64::from(v[a]) - CENTRE[a])
}

/// A ball of particles meshes to a closed surface (every edge in two triangles, Euler
/// characteristic 2) about the outermost particles: every vertex within half a spacing inside to
/// a spacing outside them (the iso-surface at 0.6 rho0 lies beyond the last layer, within the
/// kernel's reach of h = 2 spacings). Normals point out and the triangles wind
/// counter-clockwise seen from outside; the interpolated fields reproduce the particles': the
/// speed, uniform, within 1e-4, the viscosity, rising 1 m^2/s a metre, within its change over
/// a spacing (the vertices lie up to a spacing beyond the last particles, where the
/// interpolation extrapolates from one side; measured: up to that over 0.56 spacing).
#[test]
fn a_ball_of_particles_meshes_to_a_closed_surface_about_them() {
    let mesh = mesh_of_ball();
    assert!(mesh.triangles.len() > 500, "{} triangles", mesh.triangles.len());
    let n = mesh.vertices.len();
    assert!(mesh.normals.len() == n && mesh.viscosity.len() == n && mesh.speed.len() == n);
    for &v in &mesh.vertices {
        let d = from_centre(v);
        let r = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt() / SPACING;
        assert!((RADIUS - 0.5..=RADIUS + 1.0).contains(&r), "a vertex {r} spacings from the centre");
    }
    let mut edges: HashMap<(u32, u32), u32> = HashMap::new();
    for t in &mesh.triangles {
        for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
            *edges.entry((a.min(b), a.max(b))).or_default() += 1;
        }
        let [p, q, r] = t.map(|k| from_centre(mesh.vertices[k as usize]));
        let (u, w) = ([0, 1, 2].map(|a| q[a] - p[a]), [0, 1, 2].map(|a| r[a] - p[a]));
        let normal = [u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]];
        let centroid = [0, 1, 2].map(|a| p[a] + q[a] + r[a]);
        assert!((0..3).map(|a| normal[a] * centroid[a]).sum::<f64>() > 0.0, "a triangle winds inwards");
    }
    assert!(edges.values().all(|&c| c == 2), "an open or non-manifold edge");
    assert_eq!(n as i64 - edges.len() as i64 + mesh.triangles.len() as i64, 2, "Euler characteristic");
    let mut worst = 0.0_f64;
    for k in 0..n {
        let d = from_centre(mesh.vertices[k]);
        let out: f64 =
            (0..3).map(|a| d[a] * f64::from(mesh.normals[k][a])).sum::<f64>() / (d.iter().map(|c| c * c).sum::<f64>()).sqrt();
        assert!(out > 0.7, "a normal {out:.2} from the outward radius");
        assert!((mesh.speed[k] - 0.5).abs() < 1e-4, "speed {}", mesh.speed[k]);
        let expected = 0.05 + d[1];
        let error = (f64::from(mesh.viscosity[k]) - expected).abs();
        worst = worst.max(error / SPACING);
        assert!(error < SPACING, "viscosity {} against {expected}", mesh.viscosity[k]);
    }
    eprintln!("viscosity off by at most its change over {worst:.2} spacing");
}

/// The PLY holds the header's counts in the bytes that follow it.
#[test]
fn the_surface_ply_holds_what_its_header_says() {
    let mesh = mesh_of_ball();
    let ply = mesh.to_ply();
    let end = ply.windows(11).position(|w| w == b"end_header\n").expect("a header") + 11;
    let header = String::from_utf8_lossy(&ply[..end]);
    assert!(header.starts_with("ply\nformat binary_little_endian 1.0\n"), "{header}");
    assert!(header.contains(&format!("element vertex {}\n", mesh.vertices.len())), "{header}");
    assert!(header.contains(&format!("element face {}\n", mesh.triangles.len())), "{header}");
    assert_eq!(ply.len() - end, 32 * mesh.vertices.len() + 13 * mesh.triangles.len());
    let first = f32::from_le_bytes(ply[end..end + 4].try_into().expect("4 bytes"));
    assert_eq!(first, mesh.vertices[0][0]);
}

/// A picture of the ball over a plate, from the front and from above: the ball's colours at
/// the panel's centre (the top of the range: yellow, shaded no darker than the ambient light),
/// the grey plate under it in the front view, white elsewhere; the picture as wide as its
/// panels and the colour bar.
#[test]
fn a_render_shows_the_surface_over_the_plate() {
    let mesh = mesh_of_ball();
    let half = (RADIUS + 2.0) * SPACING;
    let floor = CENTRE[1] - half;
    let stage = Stage {
        min_m: [CENTRE[0] - half, floor - 2.0 * SPACING, CENTRE[2] - half],
        max_m: [CENTRE[0] + half, CENTRE[1] + half, CENTRE[2] + half],
        plate: Some((floor, 2.0 * SPACING)),
        quantity: "speed |v| (m/s)".into(),
        range: (0.0, 0.5),
        size: 200,
    };
    let image = stage.render(&mesh, &mesh.speed, 0.25, &[Camera::Front, Camera::Top]);
    assert_eq!((image.width, image.height), (2 * 200 + 150, 200 + 28));
    let at = |x: usize, y: usize| {
        let k = 3 * (y * image.width + x);
        [image.pixels[k], image.pixels[k + 1], image.pixels[k + 2]]
    };
    // The panels' centres are the stage's centre, half a spacing above the ball's.
    for x in [100, 300] {
        let [r, g, b] = at(x, 28 + 100);
        assert!(r > 80 && g > 80 && b < 60 && r <= 253 && g <= 231, "the ball at panel {x}: {:?}", [r, g, b]);
    }
    // The plate is seen edge-on in the front view, below the ball.
    // The slab's middle, a spacing below the floor, is `half` below the stage's centre.
    let plate_row = 28 + 100 + (half / (2.0 * half + 2.0 * SPACING) * 0.9 * 200.0).round() as usize;
    let [r, g, b] = at(100 + 60, plate_row);
    assert!(r == g && g == b && (150..=230).contains(&r), "the plate: {:?}", [r, g, b]);
    assert_eq!(at(5, 28 + 100), [255, 255, 255]);
}

/// `coil surface`, `coil render` and `coil pov` on a short run, whose summary names render: a
/// mesh (the same as the run's own with `output.formats` "surface"), a picture and a POV-Ray
/// scene beside every frame, a looping GIF with one picture a
/// frame; bad input exits 2 naming what is wrong.
#[test]
fn surface_and_render_commands_write_beside_the_frames() {
    let out = std::env::temp_dir().join(format!("coil-surface-{}", std::process::id()));
    std::fs::remove_dir_all(&out).ok();
    let scene = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/dam_break.toml");
    let (scene, out_arg) = (scene.to_str().expect("utf-8"), out.to_str().expect("utf-8"));
    let run = common::coil(&[
        "run",
        scene,
        "--quiet",
        "--out",
        out_arg,
        "--set",
        "material.particle_spacing_m=0.04",
        "--set",
        "simulation.end_time_s=0.04",
        "--set",
        "output.every_s=0.02",
        "--set",
        "output.formats=[\"vtu\",\"surface\"]",
    ]);
    assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
    // The summary says what to run next, and how the run's compression and Mach number stand.
    let summary = String::from_utf8_lossy(&run.stdout);
    assert!(summary.contains(&format!("next: coil render {out_arg}")) && !summary.contains("coil axis"), "{summary}");
    assert!(summary.contains("the usual aim of 0.01") && summary.contains("the usual aim of 0.1;"), "{summary}");
    let frames: Vec<_> = ["frame_000000", "frame_000001", "frame_000002"].map(|f| out.join(f)).into();
    // Meshed as the run writes each frame, and again from the frame read back: the same mesh.
    let during_run: Vec<Vec<u8>> =
        frames.iter().map(|f| std::fs::read(f.with_extension("surface.ply")).expect("a mesh")).collect();
    let surface = common::coil(&["surface", out_arg, "--quiet", "--format", "ply,obj"]);
    assert!(surface.status.success(), "{}", String::from_utf8_lossy(&surface.stderr));
    for (f, meshed) in frames.iter().zip(&during_run) {
        assert!(f.with_extension("surface.obj").is_file(), "{}", f.display());
        assert_eq!(&std::fs::read(f.with_extension("surface.ply")).expect("a mesh"), meshed, "{}", f.display());
    }
    let render = common::coil(&["render", out_arg, "--quiet", "--size", "96", "--views", "front,oblique"]);
    assert!(render.status.success(), "{}", String::from_utf8_lossy(&render.stderr));
    for f in &frames {
        let png = std::fs::read(f.with_extension("render.png")).expect("a picture");
        assert_eq!(&png[1..4], b"PNG");
    }
    let pov = common::coil(&["pov", out_arg]);
    assert!(pov.status.success(), "{}", String::from_utf8_lossy(&pov.stderr));
    for f in &frames {
        let scene = std::fs::read_to_string(f.with_extension("pov")).expect("a POV-Ray scene");
        assert!(scene.contains("blob {") && scene.contains("camera {"), "{}", f.display());
    }
    let gif = std::fs::read(out.join("render.gif")).expect("the movie");
    assert_eq!(&gif[..6], b"GIF89a");
    let pictures = gif.windows(2).filter(|w| w == &[0x21, 0xF9]).count();
    assert_eq!(pictures, frames.len(), "one graphic control block a picture");
    mp4_through_ffmpeg(&out, &String::from_utf8_lossy(&render.stdout), frames.len());
    for (args, named) in [
        (vec!["surface", "no/such/run"], "no/such/run"),
        (vec!["surface", out_arg, "--cube-size", "0"], "--cube-size"),
        (vec!["render", out_arg, "--size", "10"], "--size"),
        (vec!["render", out_arg, "--range", "2,1"], "--range"),
        (vec!["pov", out_arg, "--size", "10,10"], "--size"),
    ] {
        let bad = common::coil(&args);
        let stderr = String::from_utf8_lossy(&bad.stderr);
        assert_eq!(bad.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(stderr.contains(named) && !stderr.contains("panicked"), "{args:?}: {stderr}");
    }
    std::fs::remove_dir_all(&out).ok();
}

/// `render.mp4` beside the GIF: ffmpeg's own where it is installed, else the advice to install
/// it; then through stand-ins on the PATH, one that keeps what it is fed (the raw RGB pictures,
/// of the size and at the rate it is told) and one that fails, which leaves a
/// warning, the GIF, and no movie or partial file.
fn mp4_through_ffmpeg(out: &std::path::Path, said: &str, frames: usize) {
    let out_arg = out.to_str().expect("utf-8");
    let mp4 = out.join("render.mp4");
    if said.contains("install ffmpeg") {
        assert!(!mp4.exists(), "{said}");
    } else {
        let video = std::fs::read(&mp4).unwrap_or_else(|e| panic!("{said}: {e}"));
        assert_eq!(&video[4..8], b"ftyp", "an MP4 file starts with its ftyp box");
    }
    let bin = out.join("stand-in");
    std::fs::create_dir_all(&bin).expect("a folder for the stand-in");
    let ffmpeg = bin.join("ffmpeg");
    let render =
        || common::coil_with_path_first(&bin, &["render", out_arg, "--quiet", "--size", "96", "--views", "front,oblique"]);
    let stand_in = |script: &str| {
        use std::os::unix::fs::PermissionsExt;
        std::fs::write(&ffmpeg, script).expect("the stand-in");
        std::fs::set_permissions(&ffmpeg, std::fs::Permissions::from_mode(0o755)).expect("executable");
    };
    stand_in("#!/bin/sh\nfor last; do :; done\nprintf '%s\\n' \"$@\" > \"$(dirname \"$0\")/args\"\ncat > \"$last\"\n");
    let fed = render();
    assert!(fed.status.success(), "{}", String::from_utf8_lossy(&fed.stderr));
    let args = std::fs::read_to_string(bin.join("args")).expect("the stand-in's arguments");
    let arg_after = |flag: &str| args.lines().skip_while(|a| *a != flag).nth(1).unwrap_or_default().to_string();
    let png = std::fs::read(out.join("frame_000000.render.png")).expect("a picture");
    let dimension = |at: usize| u32::from_be_bytes(png[at..at + 4].try_into().expect("4 bytes")) as usize;
    let (width, height) = (dimension(16), dimension(20));
    assert_eq!(arg_after("-s"), format!("{width}x{height}"), "{args}");
    assert_eq!(arg_after("-framerate"), "100/8", "{args}");
    let bytes = std::fs::metadata(&mp4).expect("the stand-in's movie, renamed").len() as usize;
    assert_eq!(bytes, frames * width * height * 3, "{frames} pictures of {width}x{height} RGB");
    std::fs::remove_file(&mp4).expect("removable");
    stand_in("#!/bin/sh\ncat > /dev/null\necho \"Unknown encoder 'libx264'\" >&2\nexit 1\n");
    let failed = render();
    let stderr = String::from_utf8_lossy(&failed.stderr);
    assert!(failed.status.success(), "the pictures and the GIF stand: {stderr}");
    assert!(stderr.contains("render.mp4 not written") && stderr.contains("Unknown encoder"), "{stderr}");
    assert!(!mp4.exists() && !out.join("render.mp4.tmp").exists());
    assert!(out.join("render.gif").is_file());
}

/// The POV-Ray scene of the ball: one blob holding a sphere component of radius h per
/// particle, each with its own colour, the plate as a box, a camera and lights, every brace
/// closed. Where `povray` is installed (Debian: povray) it must render the scene; elsewhere
/// only the syntax above is checked.
#[test]
fn the_pov_scene_has_a_blob_component_per_particle_and_renders() {
    use coil::output::pov::PovStage;
    let frame = ball();
    let half = (RADIUS + 2.0) * SPACING;
    let stage = PovStage {
        min_m: [CENTRE[0] - half, CENTRE[1] - half, CENTRE[2] - half],
        max_m: [CENTRE[0] + half, CENTRE[1] + half, CENTRE[2] + half],
        plate: Some((CENTRE[1] - half, 2.0 * SPACING)),
        radius_m: 2.0 * SPACING,
        range: (0.0, 0.1),
    };
    let viscosity = &frame.scalars["viscosity"];
    let pov = stage.scene(&frame.position, viscosity, 0.5);
    assert!(pov.contains("#version 3.7;") && pov.contains("camera {") && pov.contains("light_source {"));
    assert_eq!(pov.matches("blob {").count(), 1);
    assert_eq!(pov.matches("box {").count(), 1);
    assert_eq!(pov.matches("  sphere {").count(), frame.position.len());
    assert_eq!(pov.matches(&format!(", {:.6}, 1 texture", 2.0 * SPACING)).count(), frame.position.len());
    let mut depth = 0i64;
    for c in pov.chars() {
        depth += match c {
            '{' => 1,
            '}' => -1,
            _ => 0,
        };
        assert!(depth >= 0, "a brace closed before it opened");
    }
    assert_eq!(depth, 0, "unclosed braces");
    let dir = std::env::temp_dir().join(format!("coil-pov-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("a temporary folder");
    let (scene, png) = (dir.join("ball.pov"), dir.join("ball.png"));
    std::fs::write(&scene, &pov).expect("written");
    let rendered = std::process::Command::new("povray")
        .args([format!("+I{}", scene.display()), format!("+O{}", png.display())])
        .args(["+W64", "+H48", "-D", "+FN"])
        .output();
    match rendered {
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            eprintln!("povray is not installed: the scene's syntax checked only")
        }
        Err(e) => panic!("povray: {e}"),
        Ok(o) => {
            assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
            assert_eq!(&std::fs::read(&png).expect("the picture")[1..4], b"PNG");
        }
    }
    std::fs::remove_dir_all(&dir).ok();
}
