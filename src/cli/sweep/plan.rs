//! The sweep plan file (TOML): the study, its inputs by content hash, where results go, what
//! each task may use on a cluster, the tool that wrote it, and every task with its index.
//!
//! ```toml
//! schema_version = 1
//! tool = "adam 0.1.0"
//! study = "codesign"
//! out_dir = "/home/me/out/sweep-codesign"
//! task_count = 4
//!
//! [resources]
//! time_per_task_min = 30
//! mem_per_task_mb = 2048
//! array_limit = 50
//!
//! [[inputs]]
//! role = "planner config"
//! path = "/home/me/adam-hzd/configs/planner/adam.toml"
//! sha256 = "5f0c…"
//!
//! [codesign]
//! grid = 2
//! inertia = "exact"
//!
//! [[tasks]]
//! index = 0
//! initial_m = [0.15, 0.15]
//! ```
//!
//! Paths are absolute (a cluster's nodes share the file system, not the working directory).
//! `adam sweep task` and `adam sweep collect` refuse a plan written by another version of
//! `adam`, and an input whose content no longer has the plan's hash (naming both hashes).

use anyhow::{bail, Context, Result};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// The plan file's schema version.
pub(crate) const PLAN_SCHEMA_VERSION: u32 = 1;

/// The tool that writes and reads plans and results: `adam <version>`.
pub(crate) fn tool_version() -> String {
    format!("adam {}", env!("CARGO_PKG_VERSION"))
}

/// The studies a plan can hold.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "snake_case")]
pub(crate) enum Study {
    /// The co-design convergence study: a co-design per initial design of an n × n grid.
    Codesign,
    /// The cost landscape: the fixed-design gait at every point of an n × n grid.
    Landscape,
    /// The treadmill robustness matrix: speeds, belt steps, pushes and restarts × seeds.
    Treadmill,
    /// The gait library: a task per speed, each the anchor's plan and the walk out to its
    /// speed (`planner::library::plan_speed`).
    Library,
}

impl Study {
    /// The study's name in the plan file.
    pub(crate) fn name(self) -> &'static str {
        match self {
            Study::Codesign => "codesign",
            Study::Landscape => "landscape",
            Study::Treadmill => "treadmill",
            Study::Library => "library",
        }
    }
}

/// What each task of the job array asks of the cluster.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct Resources {
    /// Wall-time limit of one task, minutes (`sbatch --time`).
    pub(crate) time_per_task_min: u32,
    /// Memory of one task, MB (`sbatch --mem`).
    pub(crate) mem_per_task_mb: u32,
    /// How many tasks of the array run at once (`--array=0-(n-1)%limit`).
    pub(crate) array_limit: u32,
}

/// An input file of the study, by content hash.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct Input {
    /// What the file is (`planner config`, `runtime config`, `gait`, `robot`).
    pub(crate) role: String,
    /// Its absolute path.
    pub(crate) path: PathBuf,
    /// SHA-256 of its content, hex.
    pub(crate) sha256: String,
}

impl Input {
    /// The input at `path` (made absolute) with the hash of its content now.
    pub(crate) fn hashed(role: &str, path: &Path) -> Result<Self> {
        let path = std::path::absolute(path)
            .with_context(|| format!("{}: making the path absolute", path.display()))?;
        let text = std::fs::read_to_string(&path)
            .with_context(|| format!("reading {} ({role})", path.display()))?;
        Ok(Self {
            role: role.to_string(),
            path,
            sha256: model::gait::sha256_hex(&text),
        })
    }

    /// Checks that the file still has the plan's content; the error names the plan, the file
    /// and both hashes.
    pub(crate) fn verify(&self, plan: &Path) -> Result<()> {
        let text = std::fs::read_to_string(&self.path).with_context(|| {
            format!(
                "{}: input '{}' {}: cannot read it",
                plan.display(),
                self.role,
                self.path.display()
            )
        })?;
        let now = model::gait::sha256_hex(&text);
        if now != self.sha256 {
            bail!(
                "{}: input '{}' {} has changed since the plan was written: SHA-256 {} in the plan, {} now; write a new plan (adam sweep plan) or restore the file",
                plan.display(),
                self.role,
                self.path.display(),
                self.sha256,
                now
            );
        }
        Ok(())
    }
}

/// The co-design and landscape studies' settings.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct DesignGrid {
    /// Grid size n (n × n tasks).
    pub(crate) grid: usize,
    /// Inertia coupling: `exact` or `alg1`.
    pub(crate) inertia: planner::config::InertiaCoupling,
    /// Landscape: where each grid solve starts (`neighbours`: the chain of inner neighbours
    /// from the initial design, as `adam codesign landscape`; `initial`: the initial gait).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(crate) start: Option<crate::cli::codesign::StartArg>,
    /// Landscape: the grid size of the convergence study whose endpoints it draws.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(crate) sweep_grid: Option<usize>,
}

/// The treadmill study's settings.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct TreadmillSettings {
    /// Seeds of every scenario.
    pub(crate) seeds: Vec<u64>,
    /// The shorter set of `adam bench treadmill --quick`.
    pub(crate) quick: bool,
}

/// The gait-library study's settings (as `adam plan library` takes them).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct LibrarySettings {
    /// The speeds, m/s, slowest first: task k plans `speeds_mps[k]`.
    pub(crate) speeds_mps: Vec<f64>,
    /// Largest relative difference between the verified and the planned step for a gait to
    /// enter the library (`adam plan library --max-step-error`).
    pub(crate) max_step_error: f64,
    /// The library file `adam sweep collect` writes (absolute; its robot is named relative to
    /// it, as `adam plan library --out` names it).
    pub(crate) library_file: PathBuf,
}

/// One task: its index and what it runs (the field of its study).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct Task {
    /// The task's index: its `$SLURM_ARRAY_TASK_ID` and its result file's name.
    pub(crate) index: usize,
    /// Co-design: the initial thigh and shin length, m.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(crate) initial_m: Option<[f64; 2]>,
    /// Landscape: the fixed thigh and shin length, m.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(crate) lengths_m: Option<[f64; 2]>,
    /// Landscape: the co-design from this initial design (thigh, shin, m) for the optimum and
    /// its multipliers.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(crate) optimum_from_m: Option<[f64; 2]>,
    /// Treadmill: the run.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(crate) treadmill: Option<runtime::sim::matrix::Run>,
    /// Gait library: the speed of the task's gait, m/s.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(crate) speed_mps: Option<f64>,
}

/// A sweep plan.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct SweepPlan {
    /// [`PLAN_SCHEMA_VERSION`].
    pub(crate) schema_version: u32,
    /// The tool that wrote it ([`tool_version`]).
    pub(crate) tool: String,
    /// The study.
    pub(crate) study: Study,
    /// Where results (`results/task-NNNNN.json`), task logs and the report go (absolute).
    pub(crate) out_dir: PathBuf,
    /// How many tasks the plan lists (a plan cut off between two tasks is refused).
    pub(crate) task_count: usize,
    /// Per task, for the cluster.
    pub(crate) resources: Resources,
    /// The input files by content hash.
    pub(crate) inputs: Vec<Input>,
    /// Co-design and landscape settings.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(crate) design: Option<DesignGrid>,
    /// Treadmill settings.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(crate) treadmill: Option<TreadmillSettings>,
    /// Gait-library settings.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(crate) library: Option<LibrarySettings>,
    /// Every task, index 0, 1, … in order.
    pub(crate) tasks: Vec<Task>,
}

impl SweepPlan {
    /// Reads a plan and checks it: this tool's version, indices 0..n in order, each task with
    /// its study's field. Errors name the file, the field and the value.
    pub(crate) fn load(path: &Path) -> Result<Self> {
        let text = std::fs::read_to_string(path)
            .with_context(|| format!("reading the sweep plan {}", path.display()))?;
        Self::parse(&text, path)
    }

    /// [`Self::load`] from the file's text.
    pub(crate) fn parse(text: &str, path: &Path) -> Result<Self> {
        let plan: SweepPlan = toml::from_str(text)
            .map_err(|e| anyhow::anyhow!("{}: not a sweep plan: {e}", path.display()))?;
        plan.validate(path)?;
        Ok(plan)
    }

    /// The checks of [`Self::load`].
    pub(crate) fn validate(&self, path: &Path) -> Result<()> {
        let file = path.display();
        if self.schema_version != PLAN_SCHEMA_VERSION {
            bail!(
                "{file}: field 'schema_version' = {}: this build reads sweep plans of version {PLAN_SCHEMA_VERSION}",
                self.schema_version
            );
        }
        if self.tool != tool_version() {
            bail!(
                "{file}: field 'tool' = \"{}\": the plan was written by another version of adam; this is \"{}\" (write the plan again with this adam, or run the adam that wrote it)",
                self.tool,
                tool_version()
            );
        }
        if self.tasks.is_empty() {
            bail!("{file}: field 'tasks': the plan has no task");
        }
        if self.tasks.len() != self.task_count {
            bail!(
                "{file}: field 'task_count' = {}, but the file lists {} tasks (cut off?)",
                self.task_count,
                self.tasks.len()
            );
        }
        let r = &self.resources;
        for (field, v) in [
            ("resources.time_per_task_min", r.time_per_task_min),
            ("resources.mem_per_task_mb", r.mem_per_task_mb),
            ("resources.array_limit", r.array_limit),
        ] {
            if v == 0 {
                bail!("{file}: field '{field}' = 0: must be at least 1");
            }
        }
        if !self.out_dir.is_absolute() {
            bail!(
                "{file}: field 'out_dir' = \"{}\": must be an absolute path",
                self.out_dir.display()
            );
        }
        for (k, t) in self.tasks.iter().enumerate() {
            if t.index != k {
                bail!(
                    "{file}: field 'tasks[{k}].index' = {}: tasks must be numbered 0, 1, … in order (expected {k})",
                    t.index
                );
            }
            let has = match self.study {
                Study::Codesign => t.initial_m.is_some(),
                Study::Landscape => {
                    t.lengths_m.is_some() || t.initial_m.is_some() || t.optimum_from_m.is_some()
                }
                Study::Treadmill => t.treadmill.is_some(),
                Study::Library => t.speed_mps.is_some(),
            };
            if !has {
                let field = match self.study {
                    Study::Codesign => "initial_m",
                    Study::Landscape => "lengths_m', 'initial_m' or 'optimum_from_m",
                    Study::Treadmill => "treadmill",
                    Study::Library => "speed_mps",
                };
                bail!(
                    "{file}: field 'tasks[{k}]': a {} task needs '{field}'",
                    self.study.name()
                );
            }
            for v in t
                .initial_m
                .iter()
                .chain(t.lengths_m.iter())
                .chain(t.optimum_from_m.iter())
                .flatten()
            {
                if !v.is_finite() || *v <= 0.0 {
                    bail!("{file}: field 'tasks[{k}]' = {v}: lengths must be positive numbers of metres");
                }
            }
        }
        match (self.study, &self.design, &self.treadmill, &self.library) {
            (Study::Codesign | Study::Landscape, None, _, _) => {
                bail!(
                    "{file}: field 'design': a {} plan needs it",
                    self.study.name()
                )
            }
            (Study::Treadmill, _, None, _) => {
                bail!("{file}: field 'treadmill': a treadmill plan needs it")
            }
            (Study::Library, _, _, None) => {
                bail!("{file}: field 'library': a library plan needs it")
            }
            (Study::Library, _, _, Some(lib)) => {
                for (k, t) in self.tasks.iter().enumerate() {
                    if t.speed_mps != lib.speeds_mps.get(k).copied() {
                        bail!(
                            "{file}: field 'tasks[{k}].speed_mps' = {:?}: task {k} plans the library's speed {k}, library.speeds_mps[{k}] = {:?}",
                            t.speed_mps,
                            lib.speeds_mps.get(k)
                        );
                    }
                }
                if lib.speeds_mps.len() != self.tasks.len() {
                    bail!(
                        "{file}: field 'library.speeds_mps': {} speeds for {} tasks (a task per speed)",
                        lib.speeds_mps.len(),
                        self.tasks.len()
                    );
                }
                let mut last = 0.0;
                for (k, &v) in lib.speeds_mps.iter().enumerate() {
                    if !(v.is_finite() && v > last) {
                        bail!(
                            "{file}: field 'library.speeds_mps[{k}]' = {v}: speeds must be positive numbers of m/s, increasing"
                        );
                    }
                    last = v;
                }
                if !(lib.max_step_error.is_finite() && lib.max_step_error > 0.0) {
                    bail!(
                        "{file}: field 'library.max_step_error' = {}: must be a positive fraction (0.01 = 1 %)",
                        lib.max_step_error
                    );
                }
                if !lib.library_file.is_absolute() {
                    bail!(
                        "{file}: field 'library.library_file' = \"{}\": must be an absolute path",
                        lib.library_file.display()
                    );
                }
            }
            _ => {}
        }
        Ok(())
    }

    /// The plan as TOML text.
    pub(crate) fn to_toml(&self) -> Result<String> {
        toml::to_string(self).context("writing the sweep plan as TOML")
    }

    /// The input of `role`.
    pub(crate) fn input(&self, role: &str, plan: &Path) -> Result<&Input> {
        self.inputs
            .iter()
            .find(|i| i.role == role)
            .with_context(|| format!("{}: field 'inputs': no input '{role}'", plan.display()))
    }

    /// Checks every input's hash ([`Input::verify`]).
    pub(crate) fn verify_inputs(&self, plan: &Path) -> Result<()> {
        self.inputs.iter().try_for_each(|i| i.verify(plan))
    }

    /// The task at `index`; the error names the plan, the index and the range.
    pub(crate) fn task(&self, index: usize, plan: &Path) -> Result<&Task> {
        self.tasks.get(index).with_context(|| {
            format!(
                "{}: task index {index} is out of range: the plan has {} tasks (0..={})",
                plan.display(),
                self.tasks.len(),
                self.tasks.len() - 1
            )
        })
    }

    /// The folder of the result files.
    pub(crate) fn results_dir(&self) -> PathBuf {
        self.out_dir.join("results")
    }

    /// The result file of task `index`.
    pub(crate) fn result_path(&self, index: usize) -> PathBuf {
        self.results_dir().join(format!("task-{index:05}.json"))
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    fn plan() -> SweepPlan {
        SweepPlan {
            schema_version: PLAN_SCHEMA_VERSION,
            tool: tool_version(),
            study: Study::Codesign,
            out_dir: PathBuf::from("/tmp/sweep"),
            task_count: 4,
            resources: Resources {
                time_per_task_min: 30,
                mem_per_task_mb: 2048,
                array_limit: 50,
            },
            inputs: vec![Input {
                role: "planner config".into(),
                path: PathBuf::from("/x/adam.toml"),
                sha256: "ab".repeat(32),
            }],
            design: Some(DesignGrid {
                grid: 2,
                inertia: planner::config::InertiaCoupling::Exact,
                start: None,
                sweep_grid: None,
            }),
            treadmill: None,
            library: None,
            tasks: (0..4)
                .map(|index| Task {
                    index,
                    // Lengths that are not short decimals: the round trip must be exact.
                    initial_m: Some([0.15 + 0.2 / 3.0 * index as f64, 0.1 + 0.1f64.sqrt()]),
                    lengths_m: None,
                    optimum_from_m: None,
                    treadmill: None,
                    speed_mps: None,
                })
                .collect(),
        }
    }

    #[test]
    fn a_plan_round_trips_through_toml_bit_for_bit() {
        let p = plan();
        let text = p.to_toml().unwrap();
        let back = SweepPlan::parse(&text, Path::new("plan.toml")).unwrap();
        assert_eq!(back, p);
        assert!(text.contains("study = \"codesign\""), "{text}");
        assert!(text.contains("[[tasks]]\nindex = 3"), "{text}");
    }

    #[test]
    fn bad_plans_are_refused_naming_the_field_and_value() {
        let err = |p: &SweepPlan| {
            SweepPlan::parse(&p.to_toml().unwrap(), Path::new("p.toml"))
                .unwrap_err()
                .to_string()
        };
        let mut p = plan();
        p.tool = "adam 0.0.1".into();
        let e = err(&p);
        assert!(e.contains("p.toml") && e.contains("\"adam 0.0.1\"") && e.contains("'tool'"));
        let mut p = plan();
        p.tasks[2].index = 7;
        let e = err(&p);
        assert!(e.contains("tasks[2].index") && e.contains("= 7"), "{e}");
        let mut p = plan();
        p.tasks[1].initial_m = Some([0.2, f64::NAN]);
        assert!(err(&p).contains("tasks[1]"));
        let mut p = plan();
        p.tasks[0].initial_m = None;
        assert!(err(&p).contains("needs 'initial_m'"));
        let mut p = plan();
        p.resources.array_limit = 0;
        assert!(err(&p).contains("resources.array_limit"));
        let e = SweepPlan::parse("study = 3", Path::new("p.toml"))
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("p.toml: not a sweep plan"), "{e}");
        let e = plan().task(4, Path::new("p.toml")).unwrap_err().to_string();
        assert!(
            e.contains("index 4 is out of range") && e.contains("4 tasks"),
            "{e}"
        );
    }

    /// A library plan: a task per speed of its settings.
    fn library_plan() -> SweepPlan {
        let speeds = vec![0.2, 0.225, 0.25];
        SweepPlan {
            study: Study::Library,
            task_count: speeds.len(),
            design: None,
            library: Some(LibrarySettings {
                speeds_mps: speeds.clone(),
                max_step_error: 0.01,
                library_file: PathBuf::from("/tmp/sweep/adam_library.json"),
            }),
            tasks: speeds
                .iter()
                .enumerate()
                .map(|(index, &v)| Task {
                    index,
                    speed_mps: Some(v),
                    ..Task::default()
                })
                .collect(),
            ..plan()
        }
    }

    #[test]
    fn library_and_landscape_plans_round_trip_and_bad_library_settings_are_named() {
        let p = library_plan();
        let back = SweepPlan::parse(&p.to_toml().unwrap(), Path::new("l.toml")).unwrap();
        assert_eq!(back, p);
        let mut l = plan();
        l.study = Study::Landscape;
        l.design = Some(DesignGrid {
            grid: 2,
            inertia: planner::config::InertiaCoupling::Exact,
            start: Some(crate::cli::codesign::StartArg::Neighbours),
            sweep_grid: Some(2),
        });
        l.tasks[3] = Task {
            index: 3,
            optimum_from_m: Some([0.24, 0.25]),
            ..Task::default()
        };
        let text = l.to_toml().unwrap();
        assert!(text.contains("start = \"neighbours\""), "{text}");
        assert_eq!(SweepPlan::parse(&text, Path::new("l.toml")).unwrap(), l);

        let err = |p: &SweepPlan| {
            SweepPlan::parse(&p.to_toml().unwrap(), Path::new("l.toml"))
                .unwrap_err()
                .to_string()
        };
        fn settings(p: &mut SweepPlan) -> &mut LibrarySettings {
            p.library.as_mut().unwrap()
        }
        let mut p = library_plan();
        settings(&mut p).speeds_mps[1] = 0.2;
        p.tasks[1].speed_mps = Some(0.2);
        let e = err(&p);
        assert!(
            e.contains("'library.speeds_mps[1]' = 0.2") && e.contains("increasing"),
            "{e}"
        );
        let mut p = library_plan();
        p.tasks[2].speed_mps = Some(0.3);
        let e = err(&p);
        assert!(e.contains("'tasks[2].speed_mps' = Some(0.3)"), "{e}");
        let mut p = library_plan();
        settings(&mut p).library_file = PathBuf::from("lib.json");
        assert!(err(&p).contains("'library.library_file' = \"lib.json\""));
        let mut p = library_plan();
        settings(&mut p).max_step_error = f64::NAN;
        assert!(err(&p).contains("'library.max_step_error' = NaN"));
        let mut p = library_plan();
        p.library = None;
        assert!(err(&p).contains("field 'library': a library plan needs it"));
        let mut p = library_plan();
        p.tasks[0].speed_mps = None;
        assert!(err(&p).contains("a library task needs 'speed_mps'"));
    }

    proptest::proptest! {
        /// Any plan of positive lengths and any index count survives TOML bit for bit.
        #[test]
        fn any_plan_round_trips(
            lengths in proptest::collection::vec((1e-6f64..10.0, 1e-6f64..10.0), 1..40),
            limit in 1u32..1000,
        ) {
            let mut p = plan();
            p.resources.array_limit = limit;
            p.task_count = lengths.len();
            p.tasks = lengths
                .iter()
                .enumerate()
                .map(|(index, &(a, b))| Task {
                    index,
                    initial_m: Some([a, b]),
                    ..Task::default()
                })
                .collect();
            let back = SweepPlan::parse(&p.to_toml().unwrap(), Path::new("p.toml")).unwrap();
            proptest::prop_assert_eq!(back, p);
        }

        /// A plan cut off anywhere (a half-copied file) is refused naming the file (cut between
        /// two tasks: by its task count), never a panic; only the whole text reads back.
        #[test]
        fn a_cut_off_plan_is_refused(cut in 0usize..2000) {
            let text = plan().to_toml().unwrap();
            let cut = cut.min(text.len());
            match SweepPlan::parse(&text[..cut], Path::new("p.toml")) {
                Err(e) => proptest::prop_assert!(e.to_string().starts_with("p.toml"), "{}", e),
                Ok(p) => {
                    proptest::prop_assert_eq!(p, plan());
                    proptest::prop_assert!(text[cut..].trim().is_empty(), "read {} of {}", cut, text.len());
                }
            }
        }
    }

    #[test]
    fn a_changed_input_is_refused_naming_both_hashes() {
        let dir = std::env::temp_dir().join(format!("adam-sweep-plan-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let file = dir.join("in.toml");
        std::fs::write(&file, "a = 1\n").unwrap();
        let input = Input::hashed("planner config", &file).unwrap();
        input.verify(Path::new("p.toml")).unwrap();
        std::fs::write(&file, "a = 2\n").unwrap();
        let e = input.verify(Path::new("p.toml")).unwrap_err().to_string();
        let now = model::gait::sha256_hex("a = 2\n");
        assert!(e.contains(&input.sha256) && e.contains(&now), "{e}");
        assert!(e.contains("in.toml") && e.contains("planner config"), "{e}");
        std::fs::remove_dir_all(&dir).ok();
    }
}
