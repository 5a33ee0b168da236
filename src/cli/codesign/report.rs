//! What `adam codesign` prints and writes: the outer iterations, the designs compared (initial,
//! co-designed, fixed), and the convergence study's CSV and Markdown table (paper Table II).

use crate::cli::plan::GaitFigures;
use model::gait::GaitFile;
use planner::codesign::{OuterIteration, SweepOutcome, SweepRun};
use planner::config::InertiaCoupling;
use std::fmt;

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
            "co-design ({:?} inertia coupling), {:.1} s in all",
            self.inertia, self.wall_time_s
        )?;
        writeln!(
            f,
            "{:>5} {:>16} {:>16} {:>8} {:>6} {:>9}",
            "outer", "start thigh/shin", "found thigh/shin", "CoT", "iter", "solve s"
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
            "design", "thigh m", "shin m", "step m", "period s", "speed m/s", "CoT"
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
        f.write_str("initial_thigh_m,initial_shin_m,status,thigh_m,shin_m,step_length_m,step_duration_s,speed_mps,cost_of_transport,iterations,solve_time_s,wall_time_s,local_minimum\n")?;
        for (r, &lm) in self.runs.iter().zip(self.local_minima) {
            match &r.outcome {
                Ok(o) => writeln!(
                    f,
                    "{},{},ok,{},{},{},{},{},{},{},{},{},{}",
                    r.initial_m[0],
                    r.initial_m[1],
                    o.lengths_m[0],
                    o.lengths_m[1],
                    o.step_length_m,
                    o.step_duration_s,
                    o.speed_mps,
                    o.cost_of_transport,
                    o.iterations,
                    o.solve_time_s,
                    r.wall_time_s,
                    lm
                )?,
                Err(e) => writeln!(
                    f,
                    "{},{},\"failed: {}\",,,,,,,,,{},",
                    r.initial_m[0],
                    r.initial_m[1],
                    e.replace('"', "'"),
                    r.wall_time_s
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
    /// Runs in all.
    pub(crate) runs: usize,
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
    /// Time to plan the warm start, s.
    pub(crate) warm_start_s: f64,
    /// Wall time of the whole study, s.
    pub(crate) wall_s: f64,
    /// Threads the runs shared.
    pub(crate) threads: usize,
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
        write!(
            f,
            "# Co-design convergence study\n\n{} runs from a {grid}×{grid} grid of initial thigh/shin lengths over [{}, {}] × [{}, {}] m, {:?} inertia coupling; warm start planned at {}/{} m in {:.1} s; {:.1} s wall time in all on {} threads.\n\n{} runs converged to the best design, {} ended in a worse local minimum (cost of transport more than {:.0} % above the best), {} failed.\n\n| quantity | mean | std | paper |\n|---|---|---|---|\n",
            self.runs, self.thigh_m[0], self.thigh_m[1], self.shin_m[0],
            self.shin_m[1], self.inertia, self.warm_start_m[0], self.warm_start_m[1], self.warm_start_s,
            self.wall_s, self.threads, self.converged, self.local_minima, self.local_minimum_margin * 100.0, self.failed
        )?;
        for (name, (m, sd), paper) in self.rows {
            writeln!(f, "| {name} | {m:.4} | {sd:.4} | {paper} |")?;
        }
        Ok(())
    }
}
