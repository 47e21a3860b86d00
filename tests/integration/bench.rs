//! `coil bench`: Table I's sizes are the particle counts the report claims, and a small run
//! writes its report files with the paper's figures beside the measured ones.

use crate::common;

use coil::bench::operation_count::{count_step_operations, counting, Counted};
use coil::bench::{dam_break, PeakRates, TABLE_I};
use coil::cpu::simulation::CpuSimulation;
use coil::scene::setup::{initial_particles, InitialParticles};
use coil::simulation::model::Model;
use coil::simulation::variant::{with_model, WithModel};
use coil_kernels::Real;
use common::coil;

#[test]
fn each_table_size_has_the_fluid_particles_its_label_names() {
    for row in &TABLE_I[..4] {
        let scene = dam_break(row.per_edge);
        let fluid = initial_particles(&scene, "dam break").expect("valid").fluid.len();
        let named: f64 = row.label.trim_end_matches('K').parse::<f64>().expect("a K label") * 1000.0;
        assert_eq!(fluid, row.per_edge.pow(3));
        // 1K = 1000 and 16K = 15625: within 5 % of the label (1024 per K or 1000 per K alike).
        assert!((fluid as f64 / named - 1.0).abs() < 0.05, "{}: {fluid}", row.label);
    }
}

#[test]
fn a_small_bench_writes_its_report_next_to_the_paper() {
    let out = std::env::temp_dir().join(format!("coil-bench-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&out);
    let o = coil(&[
        "bench",
        "--sizes",
        "1K,4K",
        "--precision",
        "f32",
        "--backend",
        "cpu",
        "--steps",
        "5",
        "--warmup",
        "2",
        "--out",
        out.to_str().expect("utf-8"),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let csv = std::fs::read_to_string(out.join("bench.csv")).expect("bench.csv");
    let rows: Vec<Vec<&str>> = csv.lines().skip(1).map(|l| l.split(',').collect()).collect();
    assert_eq!(rows.len(), 2, "{csv}");
    for (row, (label, fluid, paper_cpu)) in rows.iter().zip([("1K", "1000", "7.2"), ("4K", "4096", "35.66")]) {
        assert_eq!((row[0], row[1], row[3], row[4], row[5]), (label, fluid, "f32", "cpu", "5"));
        let median: f64 = row[6].parse().expect("median ms");
        let (p10, p90): (f64, f64) = (row[7].parse().expect("p10"), row[8].parse().expect("p90"));
        assert!(median > 0.0 && p10 <= median && median <= p90, "{row:?}");
        let (physics, filter): (f64, f64) = (row[12].parse().expect("physics operations"), row[13].parse().expect("filter"));
        assert!(physics > 0.0 && filter > 0.0 && row[14].is_empty(), "{row:?}: operations counted, no GPU floor");
        assert_eq!(row[15], paper_cpu);
    }
    let md = std::fs::read_to_string(out.join("bench.md")).expect("bench.md");
    assert!(md.contains("| 1K | 1000 |") && md.contains("| 7.200 | 1.030 | 7.0 |"), "{md}");
    let png = std::fs::read(out.join("bench.png")).expect("bench.png");
    assert_eq!(&png[1..4], b"PNG");
    let svg = std::fs::read_to_string(out.join("bench.svg")).expect("bench.svg");
    assert!(svg.starts_with("<svg"), "{svg}");
    // The plotted series: one row per point, each size's median as bench.csv holds it.
    let plotted = std::fs::read_to_string(out.join("bench.plot.csv")).expect("bench.plot.csv");
    assert!(plotted.starts_with("series,"), "{plotted}");
    for row in csv.lines().skip(1) {
        let fields: Vec<&str> = row.split(',').collect();
        let (fluid, median): (f64, f64) = (fields[1].parse().expect("fluid"), fields[6].parse().expect("median"));
        // Both files write the shortest digits that read back as the same f64.
        let plots_it = |line: &str| {
            let xy: Vec<f64> = line.rsplitn(3, ',').take(2).map(|v| v.parse().unwrap_or(f64::NAN)).collect();
            xy.len() == 2 && xy[1] == fluid && xy[0] == median
        };
        assert!(plotted.lines().any(plots_it), "{fluid} particles, {median} ms not plotted in {plotted}");
    }
    let _ = std::fs::remove_dir_all(&out);
}

#[test]
fn bench_input_mistakes_exit_2_and_say_why() {
    let o = coil(&["bench", "--sizes", "3K", "--backend", "cpu"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("`3K` is not a size of Table I"));
    if !cfg!(feature = "cuda") {
        let o = coil(&["bench", "--sizes", "1K", "--backend", "cuda"]);
        assert_eq!(o.status.code(), Some(2));
        assert!(String::from_utf8_lossy(&o.stderr).contains("--features cuda"));
    }
}

/// Positions and velocities (m, m/s) after two steps of `scene` in precision `R`.
struct TwoSteps<'a>(&'a coil::scene::Scene, &'a InitialParticles);

impl WithModel for TwoSteps<'_> {
    type Output = Vec<f64>;
    fn with<R: Real, M: Model<R>>(self, model: M) -> Vec<f64> {
        let mut sim = CpuSimulation::<R, M>::new(self.0, self.1, model);
        for _ in 0..2 {
            let (dt, limit) = sim.next_dt();
            sim.step_with(dt, limit).expect("stable");
        }
        let p = sim.particles();
        let n = p.len();
        (0..3).flat_map(|a| p.position[a][..n].iter().copied().chain(p.velocity[a][..n].iter().map(|v| v.to_f64()))).collect()
    }
}

/// The counting number type only counts: the dam break steps with it exactly as in f64.
#[test]
fn a_counted_step_is_the_f64_step() {
    let scene = dam_break(TABLE_I[0].per_edge);
    let initial = initial_particles(&scene, "dam break").expect("valid");
    let counted = with_model::<Counted, _>(&scene, TwoSteps(&scene, &initial));
    let plain = with_model::<f64, _>(&scene, TwoSteps(&scene, &initial));
    assert_eq!(counted.len(), plain.len());
    let moved = counted.iter().zip(&plain).filter(|(c, p)| c.to_bits() != p.to_bits()).count();
    assert_eq!(moved, 0, "{moved} of {} numbers differ", plain.len());
}

/// Every add, subtract, multiply, divide, square root, exp2 and log2 counts one; sign flips,
/// absolute values, comparisons and conversions count none.
#[test]
fn counted_numbers_count_each_operation_once() {
    let (value, ops) = counting(|| {
        let (a, b) = (Counted(3.0), Counted(2.0));
        let mut x = (a * b + a - b / a).sqrt();
        x += a;
        x -= b;
        x *= a;
        let y = (-x).abs().max(a).log2().exp2();
        Counted::tally_candidates(7);
        y.to_f64()
    });
    assert!((value - 3.0 * ((25.0f64 / 3.0).sqrt() + 1.0)).abs() < 1e-12, "{value}");
    assert_eq!((ops.physics, ops.candidates), (10.0, 7.0));
}

/// Each neighbor loop tallies the particles of the cells it examines: a particle alone in an
/// open domain examines itself once in each of the step's three neighbor passes (density,
/// stress, acceleration); two in one cell examine each other too. The physics of two
/// particles costs more than that of one, and the count does not depend on the threads.
#[test]
fn a_step_counts_its_neighbor_candidates_and_operations() {
    let text = |block_max: f64| {
        format!(
            "name = \"pair\"\n[material]\nparticle_spacing_m = 0.01\n[material.viscosity]\nnu0_m2_s = 0.01\n\
             [domain]\nmin_m = [0.0, 0.0, 0.0]\nmax_m = [0.2, 0.2, 0.2]\n[simulation]\nend_time_s = 0.1\n\
             [[fluid_block]]\nmin_m = [0.1, 0.1, 0.1]\nmax_m = [{block_max}, 0.105, 0.105]\n"
        )
    };
    let count = |block_max: f64, threads: usize| {
        let scene = common::scene(&text(block_max));
        let initial = initial_particles(&scene, "pair.toml").expect("valid");
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().expect("a pool");
        (initial.fluid.len(), pool.install(|| count_step_operations(&scene, &initial).expect("stable")))
    };
    let (one, single) = count(0.105, 1);
    let (two, pair) = count(0.115, 1);
    assert_eq!((one, two), (1, 2), "one particle, then two a spacing apart");
    assert_eq!(single.candidates, 3.0);
    assert_eq!(pair.candidates, 12.0);
    assert!(pair.physics > single.physics && single.physics > 0.0, "{single:?} {pair:?}");
    assert_eq!(count(0.115, 2).1, pair, "the same count on two threads");
}

/// The peak rates of two data-centre GPUs against NVIDIA's data sheets (non-tensor FP32 /
/// FP64): H100 SXM5, 132 multiprocessors at 1.98 GHz, 67 / 34 TFLOP/s; A100, 108 at
/// 1.41 GHz, 19.5 / 9.7 TFLOP/s.
#[test]
fn peak_rates_match_the_data_sheets() {
    let h100 = PeakRates::of((9, 0), 132.0, 1.98e9).expect("Hopper is listed");
    let a100 = PeakRates::of((8, 0), 108.0, 1.41e9).expect("Ampere is listed");
    for (rate, sheet) in [(h100.f32, 67e12), (h100.f64, 34e12), (a100.f32, 19.5e12), (a100.f64, 9.7e12)] {
        assert!((rate / sheet - 1.0).abs() < 0.02, "{rate:.3e} against {sheet:.3e}");
    }
    assert_eq!(PeakRates::of((3, 0), 8.0, 1e9), None, "an unlisted architecture has no peak");
}
