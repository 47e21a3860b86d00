//! `coil bench`: Table I's sizes are the particle counts the report claims, and a small run
//! writes its report files with the paper's figures beside the measured ones.

mod common;

use coil::bench::{dam_break, TABLE_I};
use coil::setup::initial_particles;
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
        assert_eq!(row[12], paper_cpu);
    }
    let md = std::fs::read_to_string(out.join("bench.md")).expect("bench.md");
    assert!(md.contains("| 1K | 1000 |") && md.contains("| 7.200 | 1.030 | 7.0 |"), "{md}");
    let png = std::fs::read(out.join("bench.png")).expect("bench.png");
    assert_eq!(&png[1..4], b"PNG");
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
