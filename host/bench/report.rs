//! The report of `coil bench`: a Markdown table beside the paper's Table I, CSV files of every
//! measurement and of the GPU's kernels, and a PNG plot of time per step against particles.

use crate::bench::{precision_name, BenchBackend, BenchOptions, BenchReport, Measurement, TABLE_I};
use crate::output::plot::{Axis, Chart, Curve, Line, PALETTE};
use crate::scene::Precision;
use std::fmt::Write;

fn find<'a>(report: &'a BenchReport, label: &str, precision: Precision, backend: BenchBackend) -> Option<&'a Measurement> {
    report.measurements.iter().find(|m| m.size.label == label && m.precision == precision && m.backend == backend)
}

fn ms(v: Option<f64>) -> String {
    v.map_or("—".into(), |v| if v < 10.0 { format!("{v:.3}") } else { format!("{v:.1}") })
}

fn ratio(v: Option<f64>) -> String {
    v.map_or("—".into(), |v| format!("{v:.1}"))
}

/// The Markdown report.
pub fn markdown(report: &BenchReport, options: &BenchOptions) -> String {
    let mut out = String::new();
    let _ = writeln!(out, "# coil bench: the dam break of the paper's Table I\n");
    let _ = writeln!(out, "- CPU: {}", report.cpu);
    let _ = writeln!(out, "- GPU: {}", report.gpu.as_deref().unwrap_or("none"));
    if let Some(b) = report.gpu_bandwidth {
        let _ = writeln!(out, "- GPU device-to-device copy bandwidth: {:.0} GB/s (read + write)", b * 1e-9);
    }
    if let Some(p) = report.gpu_peak {
        let _ = writeln!(out, "- GPU peak rates: {:.1} TFLOP/s f32, {:.1} TFLOP/s f64", p.f32 * 1e-12, p.f64 * 1e-12);
    }
    let _ = writeln!(
        out,
        "- Median ms per step over {} timed steps after {} warm-up steps; CPU sizes above 64K: {} timed steps \
         (marked *). Dam break as shipped: Cross K = 1 s, n = 1, nu0 = 0.05, nu_inf = 0.005 m^2/s, h = 2 x spacing, \
         c = 20 m/s.",
        options.steps, options.warmup, options.cpu_large_steps
    );
    let _ = writeln!(
        out,
        "- Paper: Table I's seconds per 1000 steps, i.e. ms per step; its CPU ran sequentially, its GPU is a \
         GeForce GTX 650 (384 CUDA cores).\n"
    );
    let _ = writeln!(
        out,
        "| size | fluid | boundary | precision | CPU ms | GPU ms | speedup | GPU particle-steps/s | paper CPU ms | paper GPU ms | paper speedup | paper GPU / ours |"
    );
    let _ = writeln!(out, "|---|---:|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|");
    for row in TABLE_I {
        for precision in [Precision::F32, Precision::F64] {
            let cpu = find(report, row.label, precision, BenchBackend::Cpu);
            let gpu = find(report, row.label, precision, BenchBackend::Cuda);
            let Some(any) = cpu.or(gpu) else { continue };
            let cpu_ms = cpu.map(|m| m.median_ms);
            let gpu_ms = gpu.map(|m| m.median_ms);
            let cpu_cell = match cpu {
                Some(m) if m.steps < options.steps => format!("{}*", ms(cpu_ms)),
                _ => ms(cpu_ms),
            };
            let speedup = cpu_ms.zip(gpu_ms).map(|(c, g)| c / g);
            let paper_speedup = row.paper_cpu_ms.map(|c| c / row.paper_gpu_ms);
            let _ = writeln!(
                out,
                "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
                row.label,
                any.fluid,
                any.boundary,
                precision_name(precision),
                cpu_cell,
                ms(gpu_ms),
                ratio(speedup),
                gpu.map_or("—".into(), |m| format!("{:.3e}", m.particle_steps_per_s())),
                ms(row.paper_cpu_ms),
                ms(Some(row.paper_gpu_ms)),
                ratio(paper_speedup),
                ratio(gpu_ms.map(|g| row.paper_gpu_ms / g)),
            );
        }
    }

    let _ = writeln!(out, "\n## Memory, arithmetic, and the GPU against its floors\n");
    let _ = writeln!(
        out,
        "Bytes per fluid particle: all memory the run allocated (boundary particles, the grid and scratch \
         included) over the fluid particles. The memory floor is the step's compulsory memory traffic (every \
         per-particle array each pass reads or writes, once; `bench::compulsory_bytes`) over the measured copy \
         bandwidth. Operations: a step's floating-point operations on the device, counted by running its kernels on the \
         CPU with a number type that counts them (`operation_count`): the physics, in the run's precision, plus \
         the neighbor candidates' distance filter, 8 f64 operations each in both precisions, in each of the \
         three neighbor passes. The arithmetic floor is those at the GPU's peak rates. The CPU backend filters \
         once a step, when it records the neighbor lists its three passes then read, so its achieved rate counts \
         the device's operations, not its own.\n"
    );
    let _ = writeln!(
        out,
        "| size | precision | backend | B per fluid particle | G operations (physics + f64 filter) | achieved G operations/s | memory floor ms | arithmetic floor ms | median ms | median / larger floor |"
    );
    let _ = writeln!(out, "|---|---|---|---:|---:|---:|---:|---:|---:|---:|");
    for m in &report.measurements {
        let floor = match (m.memory_floor_ms, m.arithmetic_floor_ms) {
            (Some(a), Some(b)) => Some(a.max(b)),
            (a, b) => a.or(b),
        };
        let operations = m.operations.map_or("—".into(), |o| format!("{:.3} + {:.3}", o.physics * 1e-9, o.filter_f64() * 1e-9));
        let rate =
            m.operations.map_or("—".into(), |o| format!("{:.1}", (o.physics + o.filter_f64()) / (m.median_ms * 1e-3) * 1e-9));
        let _ = writeln!(
            out,
            "| {} | {} | {} | {:.0} | {} | {} | {} | {} | {} | {} |",
            m.size.label,
            precision_name(m.precision),
            m.backend.name(),
            m.bytes_per_fluid_particle,
            operations,
            rate,
            ms(m.memory_floor_ms),
            ms(m.arithmetic_floor_ms),
            ms(Some(m.median_ms)),
            ratio(floor.map(|f| m.median_ms / f)),
        );
    }

    let largest = report.measurements.iter().filter(|m| m.backend == BenchBackend::Cuda).map(|m| m.fluid).max();
    for m in report.measurements.iter().filter(|m| Some(m.fluid) == largest && m.backend == BenchBackend::Cuda) {
        let _ = writeln!(
            out,
            "\n## GPU kernels at {} ({}), CUDA events over {} steps\n",
            m.size.label,
            precision_name(m.precision),
            options.profile_steps
        );
        let total: f64 = m.kernels.iter().map(|k| k.ms_per_step).sum();
        let _ = writeln!(out, "| kernel | launches per step | ms per step | share |");
        let _ = writeln!(out, "|---|---:|---:|---:|");
        for k in &m.kernels {
            let _ = writeln!(
                out,
                "| {} | {:.1} | {:.4} | {:.1} % |",
                k.kernel,
                k.launches_per_step,
                k.ms_per_step,
                100.0 * k.ms_per_step / total.max(1e-300)
            );
        }
        let _ = writeln!(out, "| (sum) | | {total:.4} | |");
    }
    out
}

/// One CSV line per measurement.
pub fn csv(report: &BenchReport) -> String {
    let mut out = String::from(
        "size,fluid,boundary,precision,backend,steps,median_ms,p10_ms,p90_ms,particle_steps_per_s,bytes_per_fluid_particle,memory_floor_ms,physics_operations,filter_f64_operations,arithmetic_floor_ms,paper_cpu_ms,paper_gpu_ms\n",
    );
    let opt = |v: Option<f64>| v.map_or(String::new(), |v| format!("{v}"));
    for m in &report.measurements {
        let _ = writeln!(
            out,
            "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}",
            m.size.label,
            m.fluid,
            m.boundary,
            precision_name(m.precision),
            m.backend.name(),
            m.steps,
            m.median_ms,
            m.p10_ms,
            m.p90_ms,
            m.particle_steps_per_s(),
            m.bytes_per_fluid_particle,
            opt(m.memory_floor_ms),
            opt(m.operations.map(|o| o.physics)),
            opt(m.operations.map(|o| o.filter_f64())),
            opt(m.arithmetic_floor_ms),
            opt(m.size.paper_cpu_ms),
            m.size.paper_gpu_ms
        );
    }
    out
}

/// One CSV line per kernel of each GPU measurement.
pub fn kernels_csv(report: &BenchReport) -> String {
    let mut out = String::from("size,precision,kernel,launches_per_step,ms_per_step\n");
    for m in &report.measurements {
        for k in &m.kernels {
            let _ = writeln!(
                out,
                "{},{},{},{},{}",
                m.size.label,
                precision_name(m.precision),
                k.kernel,
                k.launches_per_step,
                k.ms_per_step
            );
        }
    }
    out
}

/// ms per step against fluid particles, log-log: ours per backend and precision, the paper's
/// dashed.
pub fn chart(report: &BenchReport) -> Chart {
    let mut series = Vec::new();
    let mut colour = PALETTE.iter().copied();
    for backend in [BenchBackend::Cpu, BenchBackend::Cuda] {
        for precision in [Precision::F32, Precision::F64] {
            let points: Vec<[f64; 2]> = report
                .measurements
                .iter()
                .filter(|m| m.backend == backend && m.precision == precision)
                .map(|m| [m.fluid as f64, m.median_ms])
                .collect();
            if !points.is_empty() {
                let label = format!("coil {} {}", backend.name(), precision_name(precision));
                series.push(Curve::new(label, colour.next().unwrap_or(PALETTE[7]), points));
            }
        }
    }
    let shown: Vec<_> = TABLE_I
        .iter()
        .filter(|r| report.measurements.iter().any(|m| m.size.label == r.label))
        .map(|r| ((r.per_edge * r.per_edge * r.per_edge) as f64, r))
        .collect();
    let paper_cpu = shown.iter().filter_map(|(n, r)| r.paper_cpu_ms.map(|c| [*n, c])).collect();
    let paper_gpu = shown.iter().map(|(n, r)| [*n, r.paper_gpu_ms]).collect();
    for (label, points, c) in [("paper cpu (1 core)", paper_cpu, PALETTE[6]), ("paper gtx 650", paper_gpu, PALETTE[7])] {
        series.push(Curve { label: label.into(), color: c, points, line: Line::Dashed, marker: 3.0 });
    }
    Chart {
        title: "dam break step time (table I)".into(),
        x: Axis::log("fluid particles"),
        y: Axis::log("ms per step (median)"),
        series,
    }
}
