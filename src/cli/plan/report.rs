//! What `adam plan` prints once the gait is found: the summary table with the solver's time by
//! phase, and the one-line verification of the planned orbit.

use model::gait::GaitFile;
use planner::plan::{PlannedGait, StageReport};
use planner::verify::VerifyReport;
use std::fmt;

/// A solve's time by phase: evaluation, s, then the backend's own split (`None` where the
/// backend does not measure it: ripopt).
#[derive(Clone, Copy)]
pub(crate) struct PhaseSeconds {
    pub(crate) evaluation: f64,
    backend: Option<planner::nlp::PhaseTimes>,
}

impl PhaseSeconds {
    pub(crate) fn of(stage: &planner::plan::StageReport) -> Self {
        Self {
            evaluation: stage.evaluation_time_s,
            backend: stage.phases,
        }
    }

    /// Both stages of a plan together.
    pub(crate) fn of_plan(stages: &[planner::plan::StageReport]) -> Self {
        let start = Self {
            evaluation: 0.0,
            backend: Some(Default::default()),
        };
        stages.iter().map(Self::of).fold(start, |a, b| Self {
            evaluation: a.evaluation + b.evaluation,
            backend: planner::nlp::sum_if_both(a.backend, b.backend),
        })
    }

    /// The backend's factorization, solve and other times, s.
    pub(crate) fn split(&self) -> Option<[f64; 3]> {
        self.backend.map(|p| {
            [p.factorization_time, p.linear_solve_time, p.other_time].map(|t| t.as_secs_f64())
        })
    }

    /// The backend's three columns, 8 wide, `-` where it does not measure them.
    pub(crate) fn columns(&self) -> String {
        match self.split() {
            Some([f, s, o]) => format!("{f:>8.3} {s:>8.3} {o:>8.3}"),
            None => format!("{:>8} {:>8} {:>8}", "-", "-", "-"),
        }
    }
}

/// The gait's figures `adam plan` ends its summary with.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct GaitFigures {
    /// Step length, m.
    pub(crate) step_length_m: f64,
    /// Step duration, s.
    pub(crate) step_duration_s: f64,
    /// Speed, m/s.
    pub(crate) speed_mps: f64,
    /// Cost of transport.
    pub(crate) cost_of_transport: f64,
}

impl GaitFigures {
    /// The figures a gait file states.
    pub(crate) fn of(gait: &GaitFile) -> Self {
        Self {
            step_length_m: gait.step_length_m,
            step_duration_s: gait.step_duration_s,
            speed_mps: gait.speed_mps,
            cost_of_transport: gait.cost_of_transport,
        }
    }
}

/// `adam plan`'s summary once the gait is found: the NLP's size and set-up time, one row per
/// solve (status, iterations, restoration, objective, violation, time by phase), a footnote on
/// the columns, and the gait's figures.
pub(crate) struct PlanSummary<'a> {
    /// Variables and constraints of the cost-of-transport NLP.
    pub(crate) size: (usize, usize),
    /// Variables and constraints of the feasibility NLP, if one was solved.
    pub(crate) feasibility_size: Option<(usize, usize)>,
    /// Set-up time, s.
    pub(crate) setup_time_s: f64,
    /// One report per solve.
    pub(crate) stages: &'a [StageReport],
    /// The planned gait's figures.
    pub(crate) gait: GaitFigures,
}

impl<'a> PlanSummary<'a> {
    /// The summary of a plan.
    pub(crate) fn of(planned: &'a PlannedGait) -> Self {
        Self {
            size: planned.size,
            feasibility_size: planned.feasibility_size,
            setup_time_s: planned.setup_time_s,
            stages: &planned.stages,
            gait: GaitFigures::of(&planned.gait),
        }
    }
}

impl fmt::Display for PlanSummary<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let feasibility = self
            .feasibility_size
            .map(|(n, m)| format!(" (feasibility stage: {n} and {m}, no power slacks)"))
            .unwrap_or_default();
        writeln!(
            f,
            "NLP: {} variables, {} constraints{feasibility}, set-up {:.3} s",
            self.size.0, self.size.1, self.setup_time_s
        )?;
        writeln!(
            f,
            "{:<18} {:>8} {:>6} {:>6} {:>12} {:>10} {:>9} {:>8} {:>8} {:>8} {:>8}",
            "stage",
            "status",
            "iter",
            "resto",
            "objective",
            "violation",
            "solve s",
            "eval",
            "factor",
            "kkt sol",
            "other"
        )?;
        for s in self.stages {
            let phases = PhaseSeconds::of(s);
            writeln!(
                f,
                "{:<18} {:>8} {:>6} {:>6} {:>12.6} {:>10.1e} {:>9.3} {:>8.3} {}",
                s.stage,
                s.status,
                s.iterations,
                s.restoration_iterations
                    .map_or("-".to_string(), |n| n.to_string()),
                s.objective,
                s.violation,
                s.solve_time_s,
                s.evaluation_time_s,
                phases.columns()
            )?;
        }
        let factorizations: Option<Vec<String>> = self
            .stages
            .iter()
            .map(|s| s.phases.map(|p| p.factorizations.to_string()))
            .collect();
        writeln!(
            f,
            "(resto: iterations in feasibility restoration; eval: problem functions and derivatives; \
             factor: KKT assembly and LDLᵀ factorizations{}; kkt sol: solves with the factors; \
             other: the rest of the solver{})",
            factorizations.map_or(String::new(), |f| format!(", {} in all", f.join(" + "))),
            if self.stages.iter().any(|s| s.phases.is_none()) {
                "; -: not measured by the ripopt backend"
            } else {
                ""
            }
        )?;
        let g = &self.gait;
        write!(
            f,
            "\nstep length {:.4} m | duration {:.4} s | speed {:.4} m/s | cost of transport {:.4}",
            g.step_length_m, g.step_duration_s, g.speed_mps, g.cost_of_transport
        )
    }
}

/// Where the wall time of one whole `adam plan` went, s, and its CPU time.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct CommandTimes {
    /// Reading the robot and the config.
    pub(crate) load_s: f64,
    /// Building the problems and the starts' guesses.
    pub(crate) problems_s: f64,
    /// The feasibility solves.
    pub(crate) feasibility_s: f64,
    /// The cost-of-transport solve.
    pub(crate) cost_s: f64,
    /// The feed-forward table along the closed-loop orbit.
    pub(crate) feedforward_s: f64,
    /// The gait file: its content and writing it.
    pub(crate) write_s: f64,
    /// The verification (`adam gait check`'s work).
    pub(crate) verify_s: f64,
    /// The whole command.
    pub(crate) total_s: f64,
    /// CPU time of the whole command, all threads (`None`: not measurable here).
    pub(crate) cpu_s: Option<f64>,
}

impl CommandTimes {
    /// The phases' names and wall times, in order.
    fn phases(&self) -> [(&'static str, f64); 7] {
        [
            ("load", self.load_s),
            ("problems", self.problems_s),
            ("feasibility", self.feasibility_s),
            ("cost", self.cost_s),
            ("feed-forward", self.feedforward_s),
            ("gait file", self.write_s),
            ("verification", self.verify_s),
        ]
    }

    /// The column titles of [`Self::row`].
    pub(crate) fn header() -> String {
        let mut h: String = Self::default()
            .phases()
            .iter()
            .map(|(name, _)| format!("{name:>13}"))
            .collect();
        h.push_str(&format!("{:>13}{:>13}", "total wall", "total CPU"));
        h
    }

    /// One row of seconds under [`Self::header`].
    pub(crate) fn row(&self) -> String {
        let mut r: String = self
            .phases()
            .iter()
            .map(|(_, s)| format!("{s:>13.3}"))
            .collect();
        r.push_str(&format!(
            "{:>13.3}{:>13}",
            self.total_s,
            self.cpu_s.map_or("-".into(), |c| format!("{c:.2}"))
        ));
        r
    }

    /// Each phase's median over `runs` (so the phases need not add up to the median total).
    pub(crate) fn median(runs: &[CommandTimes]) -> CommandTimes {
        let median = |f: &dyn Fn(&CommandTimes) -> f64| {
            let mut v: Vec<f64> = runs.iter().map(f).collect();
            v.sort_by(f64::total_cmp);
            v.get(v.len() / 2).copied().unwrap_or(f64::NAN)
        };
        let cpu: Option<Vec<f64>> = runs.iter().map(|r| r.cpu_s).collect();
        CommandTimes {
            load_s: median(&|r| r.load_s),
            problems_s: median(&|r| r.problems_s),
            feasibility_s: median(&|r| r.feasibility_s),
            cost_s: median(&|r| r.cost_s),
            feedforward_s: median(&|r| r.feedforward_s),
            write_s: median(&|r| r.write_s),
            verify_s: median(&|r| r.verify_s),
            total_s: median(&|r| r.total_s),
            cpu_s: cpu.map(|mut c| {
                c.sort_by(f64::total_cmp);
                c[c.len() / 2]
            }),
        }
    }
}

impl fmt::Display for CommandTimes {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let phases: Vec<String> = self
            .phases()
            .iter()
            .map(|(name, s)| format!("{name} {s:.3}"))
            .collect();
        write!(
            f,
            "time by phase (wall s): {} | whole command {:.3} s wall, {} CPU",
            phases.join(", "),
            self.total_s,
            self.cpu_s
                .map_or("unmeasured".into(), |c| format!("{c:.2} s"))
        )
    }
}

/// The one-line verification `adam plan` prints of its gait (`adam gait check`'s figures).
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct OrbitCheck {
    /// Largest |λ| of the Poincaré map's Jacobian.
    pub(crate) spectral_radius: f64,
    /// Residual at the fixed point.
    pub(crate) fixed_point_residual: f64,
    /// Simulated step length, m.
    pub(crate) step_length_m: f64,
    /// Simulated step duration, s.
    pub(crate) step_duration_s: f64,
    /// What failed (empty: a stable periodic orbit of the plan).
    pub(crate) failures: Vec<String>,
}

impl OrbitCheck {
    /// The figures of a verification and what failed in it.
    pub(crate) fn of(report: &VerifyReport, failures: Vec<String>) -> Self {
        Self {
            spectral_radius: report.spectral_radius,
            fixed_point_residual: report.fixed_point_residual,
            step_length_m: report.step_length_m,
            step_duration_s: report.step_duration_s,
            failures,
        }
    }
}

impl fmt::Display for OrbitCheck {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "verification (adam gait check): |λ|max {:.4}, fixed-point residual {:.1e}, orbit steps \
             {:.4} m in {:.4} s, {}",
            self.spectral_radius,
            self.fixed_point_residual,
            self.step_length_m,
            self.step_duration_s,
            if self.failures.is_empty() {
                "stable periodic orbit".to_string()
            } else {
                format!("NOT a stable orbit of the plan: {}", self.failures.join("; "))
            }
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use planner::nlp::PhaseTimes;
    use std::time::Duration;

    fn stage(name: &'static str, phases: Option<PhaseTimes>) -> StageReport {
        StageReport {
            stage: name,
            status: "optimal".into(),
            iterations: 39,
            objective: 2.5e-5,
            violation: 5.9e-7,
            solve_time_s: 0.5,
            evaluation_time_s: 0.25,
            restoration_iterations: phases.map(|_| 0),
            phases,
            ..Default::default()
        }
    }

    fn native(factorizations: usize) -> PhaseTimes {
        PhaseTimes {
            factorizations,
            factorization_time: Duration::from_millis(200),
            linear_solves: 40,
            linear_solve_time: Duration::from_millis(30),
            other_time: Duration::from_millis(20),
        }
    }

    const GAIT: GaitFigures = GaitFigures {
        step_length_m: 0.15,
        step_duration_s: 0.9,
        speed_mps: 0.16667,
        cost_of_transport: 0.02074,
    };

    #[test]
    fn plan_summary_has_a_row_per_stage_with_the_native_time_by_phase() {
        let stages = [
            stage("feasibility", Some(native(83))),
            stage("cost of transport", Some(native(63))),
        ];
        let text = PlanSummary {
            size: (1258, 1245),
            feasibility_size: Some((930, 1081)),
            setup_time_s: 0.004,
            stages: &stages,
            gait: GAIT,
        }
        .to_string();
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(
            lines[0],
            "NLP: 1258 variables, 1245 constraints (feasibility stage: 930 and 1081, no power \
             slacks), set-up 0.004 s"
        );
        assert!(lines[1].starts_with("stage ") && lines[1].ends_with("   other"));
        let row: Vec<&str> = lines[2].split_whitespace().collect();
        assert_eq!(
            row,
            [
                "feasibility",
                "optimal",
                "39",
                "0",
                "0.000025",
                "5.9e-7",
                "0.500",
                "0.250",
                "0.200",
                "0.030",
                "0.020"
            ]
        );
        assert!(lines[3].starts_with("cost of transport   optimal"));
        assert!(lines[4].contains("LDLᵀ factorizations, 83 + 63 in all;"));
        assert!(!lines[4].contains("ripopt"));
        assert_eq!(lines[5], "");
        assert_eq!(
            lines[6],
            "step length 0.1500 m | duration 0.9000 s | speed 0.1667 m/s | cost of transport 0.0207"
        );
        assert_eq!(lines.len(), 7, "{text}");
    }

    #[test]
    fn plan_summary_marks_what_ripopt_does_not_measure() {
        let stages = [stage("feasibility", None), stage("cost of transport", None)];
        let text = PlanSummary {
            size: (1258, 1245),
            feasibility_size: None,
            setup_time_s: 0.004,
            stages: &stages,
            gait: GAIT,
        }
        .to_string();
        assert!(text.starts_with("NLP: 1258 variables, 1245 constraints, set-up 0.004 s\n"));
        let row = text.lines().nth(2).expect("a row");
        assert!(
            row.ends_with("    0.250        -        -        -"),
            "{row}"
        );
        assert!(row.contains("     39      -     0.000025"), "{row}");
        assert!(
            text.contains("; -: not measured by the ripopt backend)"),
            "{text}"
        );
        assert!(!text.contains("in all"), "{text}");
    }

    /// The phases are printed in order with the whole command's wall and CPU time, and the
    /// median takes each column's own median.
    #[test]
    fn command_times_print_every_phase_and_take_medians_by_column() {
        let run = |k: f64, cpu: Option<f64>| CommandTimes {
            load_s: 0.001 * k,
            problems_s: 0.01 * k,
            feasibility_s: 0.2 * k,
            cost_s: 0.3 * k,
            feedforward_s: 0.05 * k,
            write_s: 0.002 * k,
            verify_s: 0.1 * k,
            total_s: 0.7 * k,
            cpu_s: cpu,
        };
        let line = run(1.0, Some(1.25)).to_string();
        for part in [
            "load 0.001",
            "problems 0.010",
            "feasibility 0.200",
            "cost 0.300",
            "feed-forward 0.050",
            "gait file 0.002",
            "verification 0.100",
            "0.700 s wall, 1.25 s CPU",
        ] {
            assert!(line.contains(part), "{part}: {line}");
        }
        let m = CommandTimes::median(&[
            run(3.0, Some(3.0)),
            run(1.0, Some(1.0)),
            run(2.0, Some(2.0)),
        ]);
        assert_eq!(m, run(2.0, Some(2.0)));
        assert_eq!(
            CommandTimes::median(&[run(1.0, None), run(2.0, Some(2.0))]).cpu_s,
            None
        );
        assert!(CommandTimes::header().contains("verification"));
        assert_eq!(
            CommandTimes::header().len(),
            run(1.0, None).row().len(),
            "{}\n{}",
            CommandTimes::header(),
            run(1.0, None).row()
        );
    }

    #[test]
    fn orbit_check_says_stable_or_names_the_failures() {
        let mut check = OrbitCheck {
            spectral_radius: 0.86273,
            fixed_point_residual: 2.8e-9,
            step_length_m: 0.15,
            step_duration_s: 0.8999,
            failures: Vec::new(),
        };
        assert_eq!(
            check.to_string(),
            "verification (adam gait check): |λ|max 0.8627, fixed-point residual 2.8e-9, orbit \
             steps 0.1500 m in 0.8999 s, stable periodic orbit"
        );
        check.failures = vec!["unstable".into(), "not the planned pace".into()];
        assert!(check
            .to_string()
            .ends_with("NOT a stable orbit of the plan: unstable; not the planned pace"));
    }

    #[test]
    fn phase_seconds_of_a_plan_add_the_stages_and_drop_an_unmeasured_split() {
        let both =
            PhaseSeconds::of_plan(&[stage("a", Some(native(1))), stage("b", Some(native(2)))]);
        assert_eq!(both.evaluation, 0.5);
        assert_eq!(both.split(), Some([0.4, 0.06, 0.04]));
        let mixed = PhaseSeconds::of_plan(&[stage("a", Some(native(1))), stage("b", None)]);
        assert_eq!(mixed.split(), None);
        assert_eq!(mixed.columns(), "       -        -        -");
    }
}
