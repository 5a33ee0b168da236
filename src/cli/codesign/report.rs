//! What `adam codesign` prints and writes: the outer iterations, the designs compared (initial,
//! co-designed, fixed), and the convergence study's CSV and Markdown table (paper Table II).

use crate::cli::plan::GaitFigures;
use model::gait::GaitFile;
use planner::codesign::{OuterIteration, SweepOutcome, SweepRun};
use planner::config::InertiaCoupling;
use std::fmt;

/// The coupling in words: `exact` (inside the NLP) or `Alg. 1` (the paper's, between solves).
pub(crate) fn coupling_name(inertia: InertiaCoupling) -> &'static str {
    match inertia {
        InertiaCoupling::Exact => "exact",
        InertiaCoupling::Alg1 => "Alg. 1",
    }
}

/// One design and the gait found there, or why none was: a row of the design tables.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct DesignRow<'a> {
    /// What the design is (`co-designed`, `box corner`, ...).
    pub(crate) name: &'a str,
    /// Thigh and shin length, m.
    pub(crate) lengths_m: [f64; 2],
    /// The gait's figures, or the error of its optimization.
    pub(crate) gait: Result<GaitFigures, &'a str>,
}

impl<'a> DesignRow<'a> {
    /// A planned gait's row, at its own design.
    pub(crate) fn of_gait(name: &'a str, gait: &GaitFile) -> Self {
        Self {
            name,
            lengths_m: [gait.design.thigh_length_m, gait.design.shin_length_m],
            gait: Ok(GaitFigures::of(gait)),
        }
    }

    /// A gait optimized at a fixed design, or its error.
    pub(crate) fn of_outcome(
        name: &'a str,
        lengths_m: [f64; 2],
        outcome: &'a Result<SweepOutcome, String>,
    ) -> Self {
        Self {
            name,
            lengths_m,
            gait: match outcome {
                Ok(o) => Ok(GaitFigures {
                    step_length_m: o.step_length_m,
                    step_duration_s: o.step_duration_s,
                    speed_mps: o.speed_mps,
                    cost_of_transport: o.cost_of_transport,
                }),
                Err(e) => Err(e),
            },
        }
    }
}

impl fmt::Display for DesignRow<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let (name, d) = (self.name, self.lengths_m);
        match &self.gait {
            Ok(o) => write!(
                f,
                "{:<22} {:>8.4} {:>8.4} {:>9.4} {:>9.4} {:>9.4} {:>8.5}",
                name,
                d[0],
                d[1],
                o.step_length_m,
                o.step_duration_s,
                o.speed_mps,
                o.cost_of_transport
            ),
            Err(e) => write!(f, "{:<22} {:>8.4} {:>8.4} failed: {e}", name, d[0], d[1]),
        }
    }
}

/// `adam codesign`'s report: the coupling and wall time, one row per outer iteration, the
/// initial and co-designed designs, and a warning if the outer loop did not converge. Every
/// line ends with a newline.
pub(crate) struct CodesignReport<'a> {
    /// How the link inertias followed the design.
    pub(crate) inertia: InertiaCoupling,
    /// Wall time of the whole co-design, s.
    pub(crate) wall_time_s: f64,
    /// The co-design solves.
    pub(crate) outer: &'a [OuterIteration],
    /// The initial and the co-designed design.
    pub(crate) designs: [DesignRow<'a>; 2],
    /// Whether the outer loop met its tolerance.
    pub(crate) converged: bool,
}

impl fmt::Display for CodesignReport<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "co-design ({} inertia coupling), {:.1} s in all (mech CoT: the mechanical cost of \
             transport Σ∫|u q̇| dt / m g d, whatever [cost] minimizes)",
            coupling_name(self.inertia),
            self.wall_time_s
        )?;
        writeln!(
            f,
            "{:>5} {:>16} {:>16} {:>8} {:>6} {:>9}",
            "outer", "start thigh/shin", "found thigh/shin", "mech CoT", "iter", "solve s"
        )?;
        for (j, o) in self.outer.iter().enumerate() {
            writeln!(
                f,
                "{:>5} {:>7.4}/{:<8.4} {:>7.4}/{:<8.4} {:>8.5} {:>6} {:>9.2}",
                j + 1,
                o.start_m[0],
                o.start_m[1],
                o.lengths_m[0],
                o.lengths_m[1],
                o.cost_of_transport,
                o.report.iterations,
                o.report.solve_time_s
            )?;
        }
        writeln!(
            f,
            "\n{:<22} {:>8} {:>8} {:>9} {:>9} {:>9} {:>8}",
            "design", "thigh m", "shin m", "step m", "period s", "speed m/s", "mech CoT"
        )?;
        for row in &self.designs {
            writeln!(f, "{row}")?;
        }
        if !self.converged {
            writeln!(
                f,
                "warning: the outer loop stopped at its iteration limit before ‖ΔL‖ < δ"
            )?;
        }
        Ok(())
    }
}

/// `sweep.csv` of the convergence study: a header and one line per run.
pub(crate) struct SweepCsv<'a> {
    /// The runs.
    pub(crate) runs: &'a [SweepRun],
    /// Whether each run ended in a worse local minimum.
    pub(crate) local_minima: &'a [bool],
}

impl fmt::Display for SweepCsv<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        // What the runs found, nothing of their times (times.csv): the same from every path.
        f.write_str("initial_thigh_m,initial_shin_m,status,thigh_m,shin_m,step_length_m,step_duration_s,speed_mps,cost_of_transport,iterations,local_minimum\n")?;
        for (r, &lm) in self.runs.iter().zip(self.local_minima) {
            match &r.outcome {
                Ok(o) => writeln!(
                    f,
                    "{},{},ok,{},{},{},{},{},{},{},{}",
                    r.initial_m[0],
                    r.initial_m[1],
                    o.lengths_m[0],
                    o.lengths_m[1],
                    o.step_length_m,
                    o.step_duration_s,
                    o.speed_mps,
                    o.cost_of_transport,
                    o.iterations,
                    lm
                )?,
                Err(e) => writeln!(
                    f,
                    "{},{},\"failed: {}\",,,,,,,,",
                    r.initial_m[0],
                    r.initial_m[1],
                    e.replace('"', "'"),
                )?,
            }
        }
        Ok(())
    }
}

/// `table.md` of the convergence study (the paper's Table II): how the runs were made and
/// ended, then mean and standard deviation of each quantity over the runs that reached the best
/// design.
pub(crate) struct SweepTable<'a> {
    /// Runs reported (fewer than planned while results are missing).
    pub(crate) runs: usize,
    /// Runs planned (grid × grid).
    pub(crate) planned_runs: usize,
    /// Grid size n (n × n runs).
    pub(crate) grid: usize,
    /// Bounds on the thigh length, m.
    pub(crate) thigh_m: [f64; 2],
    /// Bounds on the shin length, m.
    pub(crate) shin_m: [f64; 2],
    /// Inertia coupling.
    pub(crate) inertia: InertiaCoupling,
    /// Thigh and shin length of the warm start, m.
    pub(crate) warm_start_m: [f64; 2],
    /// Runs that reached the best design.
    pub(crate) converged: usize,
    /// Runs that ended in a worse local minimum.
    pub(crate) local_minima: usize,
    /// Relative cost of transport above the best that marks a local minimum.
    pub(crate) local_minimum_margin: f64,
    /// Runs that failed.
    pub(crate) failed: usize,
    /// Quantity, (mean, std), the paper's value.
    pub(crate) rows: &'a [(&'a str, (f64, f64), &'a str)],
}

impl fmt::Display for SweepTable<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let grid = self.grid;
        let missing = self.planned_runs.saturating_sub(self.runs);
        write!(
            f,
            "# Co-design convergence study\n\n{} runs from a {grid}×{grid} grid of initial thigh/shin lengths over [{}, {}] × [{}, {}] m, {} inertia coupling, each warm-started from the gait planned at {}/{} m.{}\n\n{} runs converged to the best design, {} ended in a worse local minimum (cost of transport more than {:.0} % above the best), {} failed.\n\n| quantity | mean | std | paper |\n|---|---|---|---|\n",
            self.runs, self.thigh_m[0], self.thigh_m[1], self.shin_m[0],
            self.shin_m[1], coupling_name(self.inertia), self.warm_start_m[0], self.warm_start_m[1],
            if missing > 0 { format!(" **{missing} of {} planned runs have no result yet.**", self.planned_runs) } else { String::new() },
            self.converged, self.local_minima, self.local_minimum_margin * 100.0, self.failed
        )?;
        for (name, (m, sd), paper) in self.rows {
            writeln!(f, "| {name} | {m:.4} | {sd:.4} | {paper} |")?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const FIGURES: GaitFigures = GaitFigures {
        step_length_m: 0.15,
        step_duration_s: 0.8999,
        speed_mps: 0.16669,
        cost_of_transport: 0.013874,
    };

    #[test]
    fn a_design_row_gives_lengths_and_gait_or_the_failure() {
        let row = DesignRow {
            name: "co-designed",
            lengths_m: [0.34874, 0.35],
            gait: Ok(FIGURES),
        };
        assert_eq!(
            row.to_string(),
            "co-designed              0.3487   0.3500    0.1500    0.8999    0.1667  0.01387"
        );
        let failed: Result<SweepOutcome, String> = Err("no feasible gait".into());
        let row = DesignRow::of_outcome("box corner", [0.15, 0.35], &failed);
        assert_eq!(
            row.to_string(),
            "box corner               0.1500   0.3500 failed: no feasible gait"
        );
    }

    #[test]
    fn the_codesign_report_names_the_coupling_in_words_and_warns_when_not_converged() {
        let outer = [OuterIteration {
            start_m: [0.24, 0.25],
            lengths_m: [0.3487, 0.35],
            cost_of_transport: 0.01411,
            report: planner::plan::StageReport {
                iterations: 135,
                solve_time_s: 2.87,
                ..Default::default()
            },
        }];
        let row = |name| DesignRow {
            name,
            lengths_m: [0.24, 0.25],
            gait: Ok(FIGURES),
        };
        let report = |inertia, converged| {
            CodesignReport {
                inertia,
                wall_time_s: 4.06,
                outer: &outer,
                designs: [row("initial (fixed)"), row("co-designed")],
                converged,
            }
            .to_string()
        };
        let text = report(InertiaCoupling::Exact, true);
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(
            lines[0],
            "co-design (exact inertia coupling), 4.1 s in all (mech CoT: the mechanical cost of \
             transport Σ∫|u q̇| dt / m g d, whatever [cost] minimizes)"
        );
        assert_eq!(
            lines[2],
            "    1  0.2400/0.2500    0.3487/0.3500    0.01411    135      2.87"
        );
        assert_eq!(lines[3], "");
        assert!(lines[4].starts_with("design ") && lines[4].ends_with("CoT"));
        assert!(lines[5].starts_with("initial (fixed) ") && lines[6].starts_with("co-designed "));
        assert_eq!(lines.len(), 7);
        assert!(text.ends_with('\n'));
        let text = report(InertiaCoupling::Alg1, false);
        assert!(
            text.starts_with("co-design (Alg. 1 inertia coupling)"),
            "{text}"
        );
        assert!(text.ends_with("before ‖ΔL‖ < δ\n"), "{text}");
    }

    #[test]
    fn the_sweep_csv_has_a_line_per_run_and_quotes_a_failure() {
        let runs = [
            SweepRun {
                initial_m: [0.15, 0.15],
                outcome: Ok(SweepOutcome {
                    lengths_m: [0.3487, 0.35],
                    step_length_m: 0.15,
                    step_duration_s: 0.9,
                    speed_mps: 0.1667,
                    cost_of_transport: 0.0139,
                    objective: 0.0139,
                    iterations: 128,
                    solve_time_s: 4.8,
                }),
                wall_time_s: 4.9,
            },
            SweepRun {
                initial_m: [0.35, 0.35],
                outcome: Err("the \"cost\" stage failed".into()),
                wall_time_s: 1.5,
            },
        ];
        let csv = SweepCsv {
            runs: &runs,
            local_minima: &[true, false],
        }
        .to_string();
        let lines: Vec<&str> = csv.lines().collect();
        assert!(lines[0].starts_with("initial_thigh_m,initial_shin_m,status,"));
        assert!(lines[0].ends_with(",iterations,local_minimum"));
        assert_eq!(
            lines[1],
            "0.15,0.15,ok,0.3487,0.35,0.15,0.9,0.1667,0.0139,128,true"
        );
        assert_eq!(
            lines[2],
            "0.35,0.35,\"failed: the 'cost' stage failed\",,,,,,,,"
        );
        // As many fields on every line (a failure's empty ones included).
        let fields = |l: &str| l.split(',').count();
        assert_eq!(fields(lines[0]), fields(lines[1]));
        assert_eq!(fields(lines[0]), fields(lines[2]));
        assert_eq!(lines.len(), 3);
    }

    #[test]
    fn the_sweep_table_states_the_study_and_a_row_per_quantity() {
        let rows = [
            ("thigh length (m)", (0.34874, 0.0), "0.2425"),
            ("solver iterations", (141.5, 3.5), "—"),
        ];
        let md = SweepTable {
            runs: 3,
            planned_runs: 4,
            grid: 2,
            thigh_m: [0.15, 0.35],
            shin_m: [0.15, 0.35],
            inertia: InertiaCoupling::Exact,
            warm_start_m: [0.24, 0.25],
            converged: 3,
            local_minima: 1,
            local_minimum_margin: 0.01,
            failed: 0,
            rows: &rows,
        }
        .to_string();
        assert!(md.starts_with("# Co-design convergence study\n\n3 runs from a 2×2 grid"));
        assert!(md.contains(
            "over [0.15, 0.35] × [0.15, 0.35] m, exact inertia coupling, each warm-started from \
             the gait planned at 0.24/0.25 m. **1 of 4 planned runs have no result yet.**"
        ));
        assert!(md.contains(
            "3 runs converged to the best design, 1 ended in a worse local minimum (cost of \
             transport more than 1 % above the best), 0 failed."
        ));
        assert!(md.ends_with(
            "| quantity | mean | std | paper |\n|---|---|---|---|\n| thigh length (m) | 0.3487 | \
             0.0000 | 0.2425 |\n| solver iterations | 141.5000 | 3.5000 | — |\n"
        ));
    }
}
