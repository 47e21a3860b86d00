//! `coil validate`: the cases, which of them decide the verdict, and the table they fill.

use super::case::{CaseResult, HOURGLASS_CONTROL};
use super::divergence_free::{
    cross_poiseuille_divergence_free, huppert_divergence_free, startup_poiseuille_divergence_free, taylor_green_divergence_free,
};
use super::huppert::{huppert_implicit, huppert_spreading};
use super::hydrostatic::hydrostatic_tank;
use super::jet::{jet_buckling, jet_half_step_above_bound, jet_implicit};
use super::poiseuille::{
    cross_poiseuille, cross_poiseuille_implicit, cross_poiseuille_in, startup_poiseuille, startup_poiseuille_implicit,
    startup_poiseuille_in,
};
use super::poiseuille::{Channel, CrossLaw};
use super::taylor_green::taylor_green;
use super::torus::{torus_implicit, torus_ordering};
use super::viscous_thread::viscous_thread;
use super::viscous_thread::Treatment;
use crate::output::write_atomically;
use crate::scene::{Pressure, ViscosityOperator, Walls};
use std::fmt;
use std::path::Path;

/// A group of `coil validate`'s cases.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Group {
    /// Start-up Poiseuille flow (Morris et al. 1997), each operator.
    Poiseuille,
    /// Steady Poiseuille flow of Cross fluids.
    Cross,
    /// The hydrostatic tank.
    Tank,
    /// The Taylor-Green vortex, each operator.
    TaylorGreen,
    /// The spreading torus of Fig. 3, ordered by K.
    Torus,
    /// Huppert's viscous spreading of a released cylinder, each operator.
    Huppert,
    /// Jet buckling (Fig. 5, 6) at H/D = 12 and 3; minutes per run, so not in --quick.
    Jet,
    /// A viscous thread falling freely, against the slender-thread solution (Trouton
    /// viscosity 3 nu); each operator and pressure treatment, at 5, 8 and 12 particles across.
    Thread,
}

/// One run of the suite, giving one or more table rows.
struct Case<'a> {
    group: Group,
    /// Whether its tolerances decide the verdict; the others are shown for comparison.
    binding: bool,
    run: Box<dyn Fn() -> Result<Vec<CaseResult>, String> + 'a>,
}

impl<'a> Case<'a> {
    fn new(group: Group, binding: bool, run: impl Fn() -> Result<Vec<CaseResult>, String> + 'a) -> Self {
        Self { group, binding, run: Box::new(run) }
    }

    fn one(group: Group, binding: bool, run: impl Fn() -> Result<CaseResult, String> + 'a) -> Self {
        Self::new(group, binding, move || run().map(|r| vec![r]))
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Verdict {
    Pass,
    Fail,
    NotMet,
}

impl Verdict {
    fn of(passed: bool, binding: bool) -> Self {
        match (passed, binding) {
            (true, _) => Verdict::Pass,
            (false, true) => Verdict::Fail,
            (false, false) => Verdict::NotMet,
        }
    }
}

impl fmt::Display for Verdict {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Verdict::Pass => "pass",
            Verdict::Fail => "FAIL",
            Verdict::NotMet => "not met (shown for comparison)",
        })
    }
}

/// The cases of the suite, quick (about half an hour on 2 cores, the thread's fourteen runs 18
/// minutes of it) or full (hours); plots go to `out`.
///
/// The rule of which cases bind: the paper's operator is held to its tolerance at 30 particles
/// across (40 for the vortex); coarser runs show its convergence, and its Cross cases, which its
/// odd-even mode keeps above 3 %, are there for comparison. Under hourglass control, which
/// removes that mode, it is held to every tolerance but Huppert's, and to its Cross cases from 20
/// across (K = 100 s, n = 0.5 measured 0.031 at 10). Huppert's exponent is approached too slowly
/// by the paper's operator to meet 10 % at 8 and 10 across, with or without the control. Of the
/// jets, the paper's operator must buckle at H/D = 12 and stay straight at 3 (Fig. 5); the
/// others are Fig. 6's comparison. Solved pressure binds in the vortex, at 40 across as the
/// paper's operator does, and in the start-up channel against the explicit solver on the same
/// walls; it runs on the paper's walls alone, which slip, so its Cross channel and spreading
/// are shown for comparison (docs/divergence-free.md). The viscous thread binds from 8 across for
/// the shipped jets' formulation (the paper's operator with Eq. (8) renormalized, continuity
/// density, particle shifting: 3 % fast at 8 across); the other treatments and operators are
/// shown for comparison (docs/validation.md).
fn cases(quick: bool, out: &Path) -> Vec<Case<'_>> {
    let out = Some(out);
    let resolutions: &[usize] = if quick { &[10, 20] } else { &[10, 20, 30] };
    let cross_across = if quick { 10 } else { 20 };
    let paper = |op| op == ViscosityOperator::Stress;
    let operators = [
        (ViscosityOperator::Stress, 0.0),
        (ViscosityOperator::Stress, HOURGLASS_CONTROL),
        (ViscosityOperator::Laplacian, 0.0),
        (ViscosityOperator::Morris, 0.0),
    ];
    let controlled =
        |across| Channel { hourglass_control: HOURGLASS_CONTROL, ..Channel::morris(across, ViscosityOperator::Stress) };
    let cross_laws = [(10.0, 1.0), (10.0, 0.5), (100.0, 0.5)];
    let mut cases = Vec::new();

    for op in [ViscosityOperator::Stress, ViscosityOperator::Laplacian, ViscosityOperator::Morris] {
        for &across in resolutions {
            cases.push(Case::one(Group::Poiseuille, !paper(op) || across >= 30, move || startup_poiseuille(across, op, out)));
        }
    }
    for &across in resolutions {
        cases.push(Case::one(Group::Poiseuille, true, move || startup_poiseuille_in(&controlled(across), out)));
    }
    let implicit_multiples: &[f64] = if quick { &[10.0] } else { &[10.0, 30.0, 100.0] };
    for op in [ViscosityOperator::Stress, ViscosityOperator::Morris] {
        // Solved implicitly at 100 times the bound, Morris's operator breaks the start-up
        // channel, most likely through the mirrored ghosts, which the solve holds at the step's
        // start (docs/implicit-viscosity.md).
        let multiples = implicit_multiples.iter().filter(move |&&m| paper(op) || m <= 30.0);
        for &multiple in multiples {
            cases.push(Case::one(Group::Poiseuille, true, move || startup_poiseuille_implicit(20, op, multiple)));
        }
        cases.push(Case::one(Group::Cross, true, move || cross_poiseuille_implicit(cross_across, op, 10.0, 0.5, 10.0)));
    }
    for walls in [Walls::Paper, Walls::Mirrored] {
        cases.push(Case::one(Group::Poiseuille, true, move || startup_poiseuille_divergence_free(20, walls)));
    }
    cases.push(Case::one(Group::Cross, false, move || cross_poiseuille_divergence_free(cross_across, 10.0, 0.5)));
    for op in [ViscosityOperator::Stress, ViscosityOperator::Morris] {
        for (k, n) in cross_laws {
            cases.push(Case::one(Group::Cross, !paper(op), move || cross_poiseuille(cross_across, op, k, n, out)));
        }
    }
    for (k_s, n) in cross_laws {
        let law = CrossLaw { nu_inf_m2_s: 0.25e-6, k_s, n };
        cases.push(Case::one(Group::Cross, cross_across >= 20, move || {
            cross_poiseuille_in(&Channel { cross: Some(law), ..controlled(cross_across) }, out)
        }));
    }
    let tank_layers = if quick { 10 } else { 20 };
    for pressure in [Pressure::WeaklyCompressible, Pressure::DivergenceFree] {
        cases.push(Case::new(Group::Tank, true, move || hydrostatic_tank(tank_layers, pressure, out)));
    }
    let vortex_across = if quick { 20 } else { 40 };
    for (op, hg) in operators {
        let binding = !paper(op) || hg > 0.0 || vortex_across >= 40;
        cases.push(Case::one(Group::TaylorGreen, binding, move || taylor_green(vortex_across, op, hg, out)));
    }
    cases.push(Case::one(Group::TaylorGreen, vortex_across >= 40, move || taylor_green_divergence_free(vortex_across)));
    let torus_spacing = if quick { 0.04 } else { 0.03 };
    cases.push(Case::one(Group::Torus, true, move || torus_ordering(torus_spacing, 0.3)));
    cases.push(Case::new(Group::Torus, true, move || torus_implicit(torus_spacing, 0.3)));
    let release_across = if quick { 8 } else { 10 };
    for (op, hg) in operators {
        cases.push(Case::new(Group::Huppert, !paper(op), move || huppert_spreading(release_across, op, hg, out)));
    }
    cases.push(Case::one(Group::Huppert, true, move || huppert_implicit(release_across)));
    for walls in [Walls::Paper, Walls::Mirrored] {
        cases.push(Case::one(Group::Huppert, false, move || huppert_divergence_free(release_across, walls)));
    }
    let thread_resolutions: &[f64] = if quick { &[5.0] } else { &[5.0, 8.0, 12.0] };
    for &across in thread_resolutions {
        for op in [ViscosityOperator::Stress, ViscosityOperator::Laplacian, ViscosityOperator::Morris] {
            for treatment in Treatment::COMPARED {
                cases.push(Case::one(Group::Thread, false, move || viscous_thread(across, op, treatment, out)));
            }
        }
        for treatment in [Treatment::RENORMALIZED, Treatment::DIVERGENCE_FREE] {
            let binding = across >= 8.0 && treatment == Treatment::RENORMALIZED;
            cases.push(Case::one(Group::Thread, binding, move || {
                viscous_thread(across, ViscosityOperator::Stress, treatment, out)
            }));
        }
    }
    if !quick {
        let paper_jets = [(12.0, ViscosityOperator::Stress, 0.0, true, true), (3.0, ViscosityOperator::Stress, 0.0, false, true)];
        let fig6 = [
            (ViscosityOperator::Stress, HOURGLASS_CONTROL),
            (ViscosityOperator::Laplacian, 0.0),
            (ViscosityOperator::Morris, 0.0),
        ]
        .into_iter()
        .flat_map(|(op, hg)| [(12.0, op, hg, true, false), (3.0, op, hg, false, false)]);
        for (height_over_d, op, hg, buckles, binding) in paper_jets.into_iter().chain(fig6) {
            cases.push(Case::one(Group::Jet, binding, move || jet_buckling(height_over_d, op, hg, buckles, 0.8, out)));
        }
        for height_over_d in [12.0, 3.0] {
            cases.push(Case::one(Group::Jet, true, move || jet_implicit(height_over_d, 0.8)));
        }
        cases.push(Case::one(Group::Jet, true, move || jet_half_step_above_bound(0.6)));
    }
    cases
}

/// Runs the cases of the groups in `only` (all when empty), prints each row and writes the
/// table to `out/validate.md`; true when every binding case passes.
pub fn run(quick: bool, only: &[Group], out: &Path) -> Result<bool, String> {
    std::fs::create_dir_all(out).map_err(|e| format!("--out: {} cannot be created: {e}", out.display()))?;
    let mut table = String::from("| case | error | tolerance | result | wall s | measured as |\n|---|---:|---:|---|---:|---|\n");
    let mut all = true;
    for case in cases(quick, out).into_iter().filter(|c| only.is_empty() || only.contains(&c.group)) {
        let group = case.group;
        match (case.run)() {
            // A run that goes unstable is a result, not the end of the report.
            Err(why) => {
                let verdict = Verdict::of(false, case.binding);
                all &= verdict != Verdict::Fail;
                println!("{group:?}: {verdict}: {why}");
                table += &format!("| {group:?} | – | – | {verdict} | – | {} |\n", why.replace('|', "/"));
            }
            Ok(results) => {
                for r in results {
                    let verdict = Verdict::of(r.passed(), case.binding);
                    all &= verdict != Verdict::Fail;
                    println!(
                        "{:<70} error {:>7.4}  tolerance {:.4}  {verdict}  ({:.0} s)",
                        r.case, r.error, r.tolerance, r.wall_s
                    );
                    table += &format!(
                        "| {} | {:.4} | {:.4} | {verdict} | {:.0} | {} |\n",
                        r.case, r.error, r.tolerance, r.wall_s, r.measure
                    );
                }
            }
        }
    }
    let path = out.join("validate.md");
    write_atomically(&path, format!("# coil validate\n\n{table}").as_bytes())
        .map_err(|e| format!("{}: cannot be written: {e}", path.display()))?;
    println!("table and plots in {}", out.display());
    Ok(all)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_comparison_cases_may_miss_their_tolerance() {
        assert_eq!(Verdict::of(true, true), Verdict::Pass);
        assert_eq!(Verdict::of(true, false), Verdict::Pass);
        assert_eq!(Verdict::of(false, true), Verdict::Fail);
        assert_eq!(Verdict::of(false, false), Verdict::NotMet);
    }

    #[test]
    fn the_paper_operator_binds_at_its_finest_resolution_and_the_others_everywhere() {
        let out = Path::new("unused");
        let binding =
            |group, quick| -> Vec<bool> { cases(quick, out).iter().filter(|c| c.group == group).map(|c| c.binding).collect() };
        // Stress at 10, 20, 30; Laplacian and Morris at each; the controlled paper's at each;
        // the implicit solver on the paper's operator at 10, 30, 100 times the bound, on
        // Morris's at 10 and 30; solved pressure against the explicit solver on the paper's walls
        // and on mirrored ones.
        assert_eq!(
            binding(Group::Poiseuille, false),
            [false, false, true, true, true, true, true, true, true, true, true, true, true, true, true, true, true, true, true]
        );
        // The paper's operator, with or without the control, binds nowhere in Huppert's case,
        // nor does solved pressure on either plate.
        assert_eq!(binding(Group::Huppert, true), [false, false, true, true, true, false, false]);
        // The vortex with solved pressure binds at 40 across, as the paper's operator does.
        assert_eq!(binding(Group::TaylorGreen, true), [false, true, true, true, false]);
        assert_eq!(binding(Group::TaylorGreen, false), [true; 5]);
        // Fig. 5's two paper jets bind; Fig. 6's six comparisons do not; the implicit solver's
        // two bind; quick runs no jet.
        assert_eq!(binding(Group::Jet, false), [true, true, false, false, false, false, false, false, true, true, true]);
        assert!(binding(Group::Jet, true).is_empty());
        // The thread, each operator, density and pressure treatment at 5 across (and 8, 12 in
        // full), is shown for comparison, solved pressure too; the shipped jets' formulation
        // binds from 8 across.
        let mut full = [false; 42];
        (full[26], full[40]) = (true, true);
        assert_eq!(binding(Group::Thread, true), [false; 14]);
        assert_eq!(binding(Group::Thread, false), full);
        // The torus: its ordering, and the implicit solver against the explicit.
        assert_eq!(binding(Group::Torus, true), [true, true]);
        // The tank, with Eq. (6)'s pressure and solved, binds both ways.
        assert_eq!(binding(Group::Tank, true), [true, true]);
        assert_eq!(cases(true, out).len(), 12 + 12 + 2 + 5 + 2 + 7 + 14);
    }
}
