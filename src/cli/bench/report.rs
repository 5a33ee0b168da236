//! What `adam bench` prints: the header and a row per run, then the summary with the medians.

use crate::cli::plan::PhaseSeconds;
use planner::config::SolverBackend;
use std::fmt;
use std::path::Path;

/// The backend's name in the summary: `Native` or `Ripopt`.
fn backend_name(backend: SolverBackend) -> &'static str {
    match backend {
        SolverBackend::Native => "Native",
        SolverBackend::Ripopt => "Ripopt",
    }
}

/// One run of `adam bench check`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct CheckRow {
    /// Run number, from 1.
    pub(crate) run: usize,
    /// Wall time of the check, s.
    pub(crate) wall_s: f64,
    /// Newton iterations on the Poincaré map.
    pub(crate) newton_iterations: usize,
    /// Residual at the fixed point.
    pub(crate) fixed_point_residual: f64,
    /// Largest |λ|.
    pub(crate) spectral_radius: f64,
}

impl CheckRow {
    /// The column titles above the rows.
    pub(crate) fn header() -> String {
        format!(
            "{:>3} {:>8} {:>7} {:>12} {:>10}",
            "run", "wall s", "newton", "residual", "|λ|max"
        )
    }
}

impl fmt::Display for CheckRow {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let (run, wall) = (self.run, self.wall_s);
        write!(
            f,
            "{run:>3} {wall:>8.3} {:>7} {:>12.3e} {:>10.6}",
            self.newton_iterations, self.fixed_point_residual, self.spectral_radius
        )
    }
}

/// The last line of `adam bench check`: the median wall time and whether every report was the
/// same.
pub(crate) struct CheckSummary<'a> {
    /// The gait file checked.
    pub(crate) gait: &'a Path,
    /// Median wall time, s.
    pub(crate) median_s: f64,
    /// Checks run.
    pub(crate) runs: usize,
    /// Whether the reports were identical.
    pub(crate) identical: bool,
}

impl fmt::Display for CheckSummary<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{}: median {:.2} s over {} checks; the reports are {}",
            self.gait.display(),
            self.median_s,
            self.runs,
            if self.identical {
                "identical"
            } else {
                "NOT identical"
            }
        )
    }
}

/// One run of `adam bench plan`: set-up, both solves, the time by phase and the total.
#[derive(Clone, Copy)]
pub(crate) struct PlanRow {
    /// Run number, from 1.
    pub(crate) run: usize,
    /// Set-up time, s.
    pub(crate) setup_s: f64,
    /// Iterations of the feasibility solve.
    pub(crate) feasibility_iterations: usize,
    /// Time of the feasibility solve, s.
    pub(crate) feasibility_solve_s: f64,
    /// Iterations of the cost-of-transport solve.
    pub(crate) cost_iterations: usize,
    /// Time of the cost-of-transport solve, s.
    pub(crate) cost_solve_s: f64,
    /// Both solves' time by phase.
    pub(crate) phases: PhaseSeconds,
    /// Wall time of the whole plan, s.
    pub(crate) total_s: f64,
}

impl PlanRow {
    /// The column titles above the rows.
    pub(crate) fn header() -> String {
        format!(
            "{:>3} {:>9} {:>10} {:>11} {:>10} {:>11} {:>8} {:>8} {:>8} {:>8} {:>8}",
            "run",
            "set-up s",
            "feas. iter",
            "feas. solve",
            "cost iter",
            "cost solve",
            "eval",
            "factor",
            "kkt sol",
            "other",
            "total s"
        )
    }
}

impl fmt::Display for PlanRow {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{:>3} {:>9.3} {:>10} {:>10.3}s {:>10} {:>10.3}s {:>8.3} {} {:>8.3}",
            self.run,
            self.setup_s,
            self.feasibility_iterations,
            self.feasibility_solve_s,
            self.cost_iterations,
            self.cost_solve_s,
            self.phases.evaluation,
            self.phases.columns(),
            self.total_s
        )
    }
}

/// The summary of `adam bench plan`: the NLP's size, the median time and iterations, whether
/// the solutions were bit-identical, the median time by phase, and published anchors.
pub(crate) struct PlanSummary {
    /// Variables and constraints.
    pub(crate) size: (usize, usize),
    /// The NLP backend.
    pub(crate) backend: SolverBackend,
    /// Median wall time of a plan, s.
    pub(crate) median_total_s: f64,
    /// Median iterations of a plan (both solves).
    pub(crate) median_iterations: usize,
    /// Plans run.
    pub(crate) runs: usize,
    /// Whether every plan found the same solution, bit for bit.
    pub(crate) identical: bool,
    /// Median problem-evaluation time, s.
    pub(crate) evaluation_s: f64,
    /// Median factorization, solve and other times of the backend, s (`None` for ripopt).
    pub(crate) split_s: Option<[f64; 3]>,
}

impl fmt::Display for PlanSummary {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let runs = self.runs;
        writeln!(
            f,
            "ADAM, {} variables, {} constraints, {} backend: median {:.2} s and {} iterations over \
             {runs} plan{} (set-up, both solves and the feed-forward table); {}",
            self.size.0,
            self.size.1,
            backend_name(self.backend),
            self.median_total_s,
            self.median_iterations,
            if runs == 1 { "" } else { "s" },
            match (runs, self.identical) {
                (1, _) => "one run, no solutions to compare",
                (_, true) => "the solutions are bit-identical",
                (_, false) => "the solutions are NOT bit-identical",
            }
        )?;
        let split = match self.split_s {
            Some([factor, solve, other]) => format!(
                "factorizations {factor:.3} s, solves with the factors {solve:.3} s, other {other:.3} s"
            ),
            None => "the backend's own time is not split (ripopt does not time its phases)".into(),
        };
        writeln!(
            f,
            "time by phase (medians): problem evaluation {:.3} s, {split}",
            self.evaluation_s
        )?;
        write!(
            f,
            "anchors: CasADi + IPOPT + MUMPS on the same kind of problem (PLANNER-NOTES) 1.19 s solve \
             + 1.96 s set-up; a published five-link optimization (571 variables) 143 IPOPT iterations, ~12 s in MATLAB"
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn check_rows_line_up_under_their_header_and_the_summary_says_identical() {
        let header = CheckRow::header();
        let row = CheckRow {
            run: 1,
            wall_s: 4.6221,
            newton_iterations: 2,
            fixed_point_residual: 2.822e-9,
            spectral_radius: 0.8627314,
        }
        .to_string();
        assert_eq!(header, "run   wall s  newton     residual     |λ|max");
        assert_eq!(row, "  1    4.622       2     2.822e-9   0.862731");
        let summary = |identical| {
            CheckSummary {
                gait: Path::new("configs/gaits/adam_walk.json"),
                median_s: 4.785,
                runs: 2,
                identical,
            }
            .to_string()
        };
        assert_eq!(
            summary(true),
            "configs/gaits/adam_walk.json: median 4.79 s over 2 checks; the reports are identical"
        );
        assert!(summary(false).ends_with("the reports are NOT identical"));
    }

    fn plan_summary(runs: usize, split_s: Option<[f64; 3]>) -> String {
        PlanSummary {
            size: (1258, 1245),
            backend: if split_s.is_some() {
                SolverBackend::Native
            } else {
                SolverBackend::Ripopt
            },
            median_total_s: 1.207,
            median_iterations: 67,
            runs,
            identical: true,
            evaluation_s: 0.482,
            split_s,
        }
        .to_string()
    }

    #[test]
    fn plan_summary_gives_medians_the_backend_and_its_time_by_phase() {
        let text = plan_summary(3, Some([0.59, 0.024, 0.021]));
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(
            lines[0],
            "ADAM, 1258 variables, 1245 constraints, Native backend: median 1.21 s and 67 \
             iterations over 3 plans (set-up, both solves and the feed-forward table); the \
             solutions are bit-identical"
        );
        assert_eq!(
            lines[1],
            "time by phase (medians): problem evaluation 0.482 s, factorizations 0.590 s, solves \
             with the factors 0.024 s, other 0.021 s"
        );
        assert!(lines[2].starts_with("anchors: CasADi + IPOPT + MUMPS"));
        assert_eq!(lines.len(), 3);
    }

    #[test]
    fn plan_summary_of_one_ripopt_run_compares_nothing_and_splits_nothing() {
        let text = plan_summary(1, None);
        assert!(text.contains("Ripopt backend: median"), "{text}");
        assert!(
            text.contains("over 1 plan (set-up")
                && text.contains("; one run, no solutions to compare\n"),
            "{text}"
        );
        assert!(
            text.contains("the backend's own time is not split (ripopt does not time its phases)"),
            "{text}"
        );
    }

    #[test]
    fn plan_rows_have_the_header_s_columns() {
        let header = PlanRow::header();
        let row = PlanRow {
            run: 2,
            setup_s: 0.003,
            feasibility_iterations: 39,
            feasibility_solve_s: 0.588,
            cost_iterations: 28,
            cost_solve_s: 0.525,
            phases: PhaseSeconds::of(&planner::plan::StageReport {
                evaluation_time_s: 0.482,
                ..Default::default()
            }),
            total_s: 1.189,
        }
        .to_string();
        assert_eq!(header.split_whitespace().next(), Some("run"));
        assert_eq!(row.len(), header.len(), "{header}\n{row}");
        assert_eq!(
            row,
            "  2     0.003         39      0.588s         28      0.525s    0.482        -        -        -    1.189"
        );
    }
}
