//! Hock–Schittkowski test problems solved through `planner::nlp` with exact
//! derivatives from `DenseAdProblem`.
//!
//! Formulations, starting points and optimal objective values are those of
//! W. Hock and K. Schittkowski, *Test Examples for Nonlinear Programming
//! Codes*, Lecture Notes in Economics and Mathematical Systems 187, Springer
//! 1981 (and K. Schittkowski, *More Test Examples…*, 1987 / the 306-problem
//! collection where it corrects a value, noted per problem). The standard
//! starting points are used, including the infeasible ones.
//!
//! Pass criterion per problem: status Optimal or Acceptable, constraint
//! violation ≤ 1e-6, and |f − f*| ≤ 1e-6·|f*| (absolute 1e-6 when f* = 0).
//! Run with `--nocapture` to see the table.

#![allow(clippy::unwrap_used)]

use std::f64::consts::PI;
use std::marker::PhantomData;

use num_dual::DualNum;
use planner::nlp::ad::{AdModel, DenseAdProblem};
use planner::nlp::{solve, Backend, SolveOptions};

const INF: f64 = f64::INFINITY;

/// Problems that do not meet the pass criterion, with the reason. The test
/// also fails if one of them starts passing, so this list stays true.
///
/// Cross-checked with IPOPT 3.14 + MUMPS (CasADi, same formulation and start):
/// IPOPT ends at the same points on HS2, HS13, HS20 and HS44; HS16 is a real
/// ripopt weakness (IPOPT reaches 0.25).
const KNOWN_FAILURES: &[(&str, &str)] = &[
    ("HS2", "local minimum f = 4.9412 at x1 ≈ -1.22 from the standard start (IPOPT: same)"),
    ("HS13", "degenerate: no constraint qualification at x* = (1, 0); stops at f = 0.994 (IPOPT: 0.9946)"),
    ("HS16", "ripopt ends at the local minimum f = 23.14; IPOPT reaches 0.25 from the same start"),
    ("HS20", "local minimum f = 40.199 at x = (-0.5, √3/2), mirror of the global one (IPOPT: same)"),
    ("HS44", "nonconvex bilinear: local minimum f = -13 at another vertex (IPOPT: same)"),
    ("HS108", "degenerate (dependent active constraints at the hexagon): Acceptable at f = -0.675"),
    ("HS116", "reaches 97.58747, below the published 97.588409 and feasible to 1e-8: a better point"),
];

/// Where the native interior point (`Backend::Native`) does not reach the published optimum.
const KNOWN_FAILURES_NATIVE: &[(&str, &str)] = &[
    ("HS2", "local minimum f = 4.9412 from the standard start (ripopt, IPOPT: same)"),
    ("HS13", "degenerate (no constraint qualification at x* = (1, 0)): ends with a numerical error at f = 0.987, feasible to 2e-7 (ripopt stops at 0.994, IPOPT at 0.9946)"),
    ("HS20", "local minimum f = 40.199 at the mirror vertex (ripopt, IPOPT: same)"),
    ("HS44", "nonconvex bilinear: local minimum f = -13 (ripopt, IPOPT: same)"),
    ("HS108", "degenerate: converges to the non-optimal KKT point f = -0.5 (ripopt stops at -0.762)"),
    ("HS116", "reaches 97.58747, below the published 97.588409 and feasible: the better point ripopt finds too"),
];

thread_local! {
    /// The backend `run` solves with (one per test thread).
    static BACKEND: std::cell::Cell<Backend> = const { std::cell::Cell::new(Backend::Ripopt) };
}

trait HsFunctions {
    fn objective<D: DualNum<Primitive = f64> + Copy>(x: &[D]) -> D;
    fn constraints<D: DualNum<Primitive = f64> + Copy>(x: &[D], g: &mut [D]);
}

macro_rules! hs {
    ($ty:ident, f: |$x:ident| $f:expr, g: |$gx:ident, $g:ident| $gbody:block) => {
        struct $ty;
        impl HsFunctions for $ty {
            fn objective<D: DualNum<Primitive = f64> + Copy>($x: &[D]) -> D {
                $f
            }
            #[allow(unused_variables)]
            fn constraints<D: DualNum<Primitive = f64> + Copy>($gx: &[D], $g: &mut [D]) {
                $gbody
            }
        }
    };
    ($ty:ident, f: |$x:ident| $f:expr) => {
        hs!($ty, f: |$x| $f, g: |x, g| {});
    };
}

/// Data of one problem: name, start, bounds, constraint bounds, published optimum.
#[derive(Clone)]
struct Spec {
    name: &'static str,
    x0: Vec<f64>,
    x_lower: Vec<f64>,
    x_upper: Vec<f64>,
    g_lower: Vec<f64>,
    g_upper: Vec<f64>,
    published: f64,
}

impl Spec {
    fn new(name: &'static str, x0: &[f64], published: f64) -> Self {
        Self {
            name,
            x0: x0.to_vec(),
            x_lower: vec![-INF; x0.len()],
            x_upper: vec![INF; x0.len()],
            g_lower: vec![],
            g_upper: vec![],
            published,
        }
    }
    fn bounds(mut self, lower: &[f64], upper: &[f64]) -> Self {
        self.x_lower = lower.to_vec();
        self.x_upper = upper.to_vec();
        self
    }
    /// Appends `count` constraints `g ≥ 0`.
    fn ge(mut self, count: usize) -> Self {
        self.g_lower.extend(std::iter::repeat_n(0.0, count));
        self.g_upper.extend(std::iter::repeat_n(INF, count));
        self
    }
    /// Appends `count` constraints `g = 0`.
    fn eq(mut self, count: usize) -> Self {
        self.g_lower.extend(std::iter::repeat_n(0.0, count));
        self.g_upper.extend(std::iter::repeat_n(0.0, count));
        self
    }
    /// Appends one constraint `lower ≤ g ≤ upper`.
    fn range(mut self, lower: f64, upper: f64) -> Self {
        self.g_lower.push(lower);
        self.g_upper.push(upper);
        self
    }
}

struct HsModel<F> {
    spec: Spec,
    functions: PhantomData<F>,
}

impl<F: HsFunctions> AdModel for HsModel<F> {
    fn num_variables(&self) -> usize {
        self.spec.x0.len()
    }
    fn num_constraints(&self) -> usize {
        self.spec.g_lower.len()
    }
    fn variable_bounds(&self, lower: &mut [f64], upper: &mut [f64]) {
        lower.copy_from_slice(&self.spec.x_lower);
        upper.copy_from_slice(&self.spec.x_upper);
    }
    fn constraint_bounds(&self, lower: &mut [f64], upper: &mut [f64]) {
        lower.copy_from_slice(&self.spec.g_lower);
        upper.copy_from_slice(&self.spec.g_upper);
    }
    fn initial_point(&self, x0: &mut [f64]) {
        x0.copy_from_slice(&self.spec.x0);
    }
    fn objective<D: DualNum<Primitive = f64> + Copy>(&self, x: &[D]) -> D {
        F::objective(x)
    }
    fn constraints<D: DualNum<Primitive = f64> + Copy>(&self, x: &[D], g: &mut [D]) {
        F::constraints(x, g)
    }
}

struct Row {
    name: &'static str,
    n: usize,
    m: usize,
    iterations: usize,
    objective: f64,
    published: f64,
    error: f64,
    infeasibility: f64,
    status: String,
    passed: bool,
}

fn run<F: HsFunctions>(spec: Spec) -> Row {
    let (name, published) = (spec.name, spec.published);
    let problem = DenseAdProblem::new(HsModel::<F> {
        spec,
        functions: PhantomData,
    });
    let model = problem.model();
    let (n, m) = (model.num_variables(), model.num_constraints());
    let options = SolveOptions {
        backend: BACKEND.with(|b| b.get()),
        ..SolveOptions::default()
    };
    let solution = solve(&problem, &options).unwrap();
    let stats = solution.statistics;
    let error = if published == 0.0 {
        stats.objective.abs()
    } else {
        (stats.objective - published).abs() / published.abs()
    };
    let passed =
        solution.status.is_success() && error <= 1e-6 && stats.primal_infeasibility <= 1e-6;
    Row {
        name,
        n,
        m,
        iterations: stats.iterations,
        objective: stats.objective,
        published,
        error,
        infeasibility: stats.primal_infeasibility,
        status: format!("{:?}", solution.status),
        passed,
    }
}

// ---------------------------------------------------------------- problems

hs!(Hs1, f: |x| (x[1] - x[0] * x[0]).powi(2) * 100.0 + (-x[0] + 1.0).powi(2));
hs!(Hs3, f: |x| x[1] + (x[1] - x[0]).powi(2) * 1e-5);
hs!(Hs4, f: |x| (x[0] + 1.0).powi(3) / 3.0 + x[1]);
hs!(Hs5, f: |x| (x[0] + x[1]).sin() + (x[0] - x[1]).powi(2) - x[0] * 1.5 + x[1] * 2.5 + 1.0);
hs!(Hs6, f: |x| (-x[0] + 1.0).powi(2), g: |x, g| { g[0] = (x[1] - x[0] * x[0]) * 10.0; });
hs!(Hs7, f: |x| (x[0] * x[0] + 1.0).ln() - x[1],
    g: |x, g| { g[0] = (x[0] * x[0] + 1.0).powi(2) + x[1] * x[1] - 4.0; });
hs!(Hs8, f: |x| x[0] * 0.0 - 1.0,
    g: |x, g| { g[0] = x[0] * x[0] + x[1] * x[1] - 25.0; g[1] = x[0] * x[1] - 9.0; });
hs!(Hs9, f: |x| (x[0] * (PI / 12.0)).sin() * (x[1] * (PI / 16.0)).cos(),
    g: |x, g| { g[0] = x[0] * 4.0 - x[1] * 3.0; });
hs!(Hs10, f: |x| x[0] - x[1],
    g: |x, g| { g[0] = x[0] * x[0] * -3.0 + x[0] * x[1] * 2.0 - x[1] * x[1] + 1.0; });
hs!(Hs11, f: |x| (x[0] - 5.0).powi(2) + x[1] * x[1] - 25.0,
    g: |x, g| { g[0] = -x[0] * x[0] + x[1]; });
hs!(Hs12, f: |x| x[0] * x[0] * 0.5 + x[1] * x[1] - x[0] * x[1] - x[0] * 7.0 - x[1] * 7.0,
    g: |x, g| { g[0] = -x[0] * x[0] * 4.0 - x[1] * x[1] + 25.0; });
hs!(Hs13, f: |x| (x[0] - 2.0).powi(2) + x[1] * x[1],
    g: |x, g| { g[0] = (-x[0] + 1.0).powi(3) - x[1]; });
hs!(Hs14, f: |x| (x[0] - 2.0).powi(2) + (x[1] - 1.0).powi(2),
    g: |x, g| { g[0] = x[0] * x[0] * -0.25 - x[1] * x[1] + 1.0; g[1] = x[0] - x[1] * 2.0 + 1.0; });
hs!(Hs15, f: |x| (x[1] - x[0] * x[0]).powi(2) * 100.0 + (-x[0] + 1.0).powi(2),
    g: |x, g| { g[0] = x[0] * x[1] - 1.0; g[1] = x[0] + x[1] * x[1]; });
hs!(Hs16, f: |x| (x[1] - x[0] * x[0]).powi(2) * 100.0 + (-x[0] + 1.0).powi(2),
    g: |x, g| { g[0] = x[0] + x[1] * x[1]; g[1] = x[0] * x[0] + x[1]; });
hs!(Hs17, f: |x| (x[1] - x[0] * x[0]).powi(2) * 100.0 + (-x[0] + 1.0).powi(2),
    g: |x, g| { g[0] = x[1] * x[1] - x[0]; g[1] = x[0] * x[0] - x[1]; });
hs!(Hs18, f: |x| x[0] * x[0] * 0.01 + x[1] * x[1],
    g: |x, g| { g[0] = x[0] * x[1] - 25.0; g[1] = x[0] * x[0] + x[1] * x[1] - 25.0; });
hs!(Hs19, f: |x| (x[0] - 10.0).powi(3) + (x[1] - 20.0).powi(3),
g: |x, g| {
    g[0] = (x[0] - 5.0).powi(2) + (x[1] - 5.0).powi(2) - 100.0;
    g[1] = -(x[1] - 5.0).powi(2) - (x[0] - 6.0).powi(2) + 82.81;
});
hs!(Hs20, f: |x| (x[1] - x[0] * x[0]).powi(2) * 100.0 + (-x[0] + 1.0).powi(2),
g: |x, g| {
    g[0] = x[0] + x[1] * x[1];
    g[1] = x[0] * x[0] + x[1];
    g[2] = x[0] * x[0] + x[1] * x[1] - 1.0;
});
hs!(Hs21, f: |x| x[0] * x[0] * 0.01 + x[1] * x[1] - 100.0,
    g: |x, g| { g[0] = x[0] * 10.0 - x[1] - 10.0; });
hs!(Hs22, f: |x| (x[0] - 2.0).powi(2) + (x[1] - 1.0).powi(2),
    g: |x, g| { g[0] = -x[0] - x[1] + 2.0; g[1] = -x[0] * x[0] + x[1]; });
hs!(Hs23, f: |x| x[0] * x[0] + x[1] * x[1],
g: |x, g| {
    g[0] = x[0] + x[1] - 1.0;
    g[1] = x[0] * x[0] + x[1] * x[1] - 1.0;
    g[2] = x[0] * x[0] * 9.0 + x[1] * x[1] - 9.0;
    g[3] = x[0] * x[0] - x[1];
    g[4] = x[1] * x[1] - x[0];
});
hs!(Hs24, f: |x| ((x[0] - 3.0).powi(2) - 9.0) * x[1].powi(3) / (27.0 * 3f64.sqrt()),
g: |x, g| {
    g[0] = x[0] / 3f64.sqrt() - x[1];
    g[1] = x[0] + x[1] * 3f64.sqrt();
    g[2] = -x[0] - x[1] * 3f64.sqrt() + 6.0;
});
hs!(Hs26, f: |x| (x[0] - x[1]).powi(2) + (x[1] - x[2]).powi(4),
    g: |x, g| { g[0] = (x[1] * x[1] + 1.0) * x[0] + x[2].powi(4) - 3.0; });
hs!(Hs27, f: |x| (x[0] - 1.0).powi(2) * 0.01 + (x[1] - x[0] * x[0]).powi(2),
    g: |x, g| { g[0] = x[0] + x[2] * x[2] + 1.0; });
hs!(Hs28, f: |x| (x[0] + x[1]).powi(2) + (x[1] + x[2]).powi(2),
    g: |x, g| { g[0] = x[0] + x[1] * 2.0 + x[2] * 3.0 - 1.0; });
hs!(Hs29, f: |x| -x[0] * x[1] * x[2],
    g: |x, g| { g[0] = -x[0] * x[0] - x[1] * x[1] * 2.0 - x[2] * x[2] * 4.0 + 48.0; });
hs!(Hs30, f: |x| x[0] * x[0] + x[1] * x[1] + x[2] * x[2],
    g: |x, g| { g[0] = x[0] * x[0] + x[1] * x[1] - 1.0; });
hs!(Hs31, f: |x| x[0] * x[0] * 9.0 + x[1] * x[1] + x[2] * x[2] * 9.0,
    g: |x, g| { g[0] = x[0] * x[1] - 1.0; });
hs!(Hs32, f: |x| (x[0] + x[1] * 3.0 + x[2]).powi(2) + (x[0] - x[1]).powi(2) * 4.0,
g: |x, g| {
    g[0] = x[1] * 6.0 + x[2] * 4.0 - x[0].powi(3) - 3.0;
    g[1] = -x[0] - x[1] - x[2] + 1.0;
});
hs!(Hs33, f: |x| (x[0] - 1.0) * (x[0] - 2.0) * (x[0] - 3.0) + x[2],
g: |x, g| {
    g[0] = x[2] * x[2] - x[1] * x[1] - x[0] * x[0];
    g[1] = x[0] * x[0] + x[1] * x[1] + x[2] * x[2] - 4.0;
});
hs!(Hs34, f: |x| -x[0],
    g: |x, g| { g[0] = x[1] - x[0].exp(); g[1] = x[2] - x[1].exp(); });
hs!(Hs35, f: |x| -x[0] * 8.0 - x[1] * 6.0 - x[2] * 4.0 + x[0] * x[0] * 2.0 + x[1] * x[1] * 2.0
        + x[2] * x[2] + x[0] * x[1] * 2.0 + x[0] * x[2] * 2.0 + 9.0,
    g: |x, g| { g[0] = -x[0] - x[1] - x[2] * 2.0 + 3.0; });
hs!(Hs36, f: |x| -x[0] * x[1] * x[2],
    g: |x, g| { g[0] = -x[0] - x[1] * 2.0 - x[2] * 2.0 + 72.0; });
hs!(Hs37, f: |x| -x[0] * x[1] * x[2],
    g: |x, g| { g[0] = -x[0] - x[1] * 2.0 - x[2] * 2.0 + 72.0; g[1] = x[0] + x[1] * 2.0 + x[2] * 2.0; });
hs!(Hs38, f: |x| (x[1] - x[0] * x[0]).powi(2) * 100.0 + (-x[0] + 1.0).powi(2)
        + (x[3] - x[2] * x[2]).powi(2) * 90.0 + (-x[2] + 1.0).powi(2)
        + ((x[1] - 1.0).powi(2) + (x[3] - 1.0).powi(2)) * 10.1 + (x[1] - 1.0) * (x[3] - 1.0) * 19.8);
hs!(Hs39, f: |x| -x[0],
g: |x, g| {
    g[0] = x[1] - x[0].powi(3) - x[2] * x[2];
    g[1] = x[0] * x[0] - x[1] - x[3] * x[3];
});
hs!(Hs40, f: |x| -x[0] * x[1] * x[2] * x[3],
g: |x, g| {
    g[0] = x[0].powi(3) + x[1] * x[1] - 1.0;
    g[1] = x[0] * x[0] * x[3] - x[2];
    g[2] = x[3] * x[3] - x[1];
});
hs!(Hs41, f: |x| -x[0] * x[1] * x[2] + 2.0,
    g: |x, g| { g[0] = x[0] + x[1] * 2.0 + x[2] * 2.0 - x[3]; });
hs!(Hs42, f: |x| (x[0] - 1.0).powi(2) + (x[1] - 2.0).powi(2) + (x[2] - 3.0).powi(2) + (x[3] - 4.0).powi(2),
    g: |x, g| { g[0] = x[0] - 2.0; g[1] = x[2] * x[2] + x[3] * x[3] - 2.0; });
hs!(Hs43, f: |x| x[0] * x[0] + x[1] * x[1] + x[2] * x[2] * 2.0 + x[3] * x[3]
    - x[0] * 5.0 - x[1] * 5.0 - x[2] * 21.0 + x[3] * 7.0,
g: |x, g| {
    g[0] = -x[0] * x[0] - x[1] * x[1] - x[2] * x[2] - x[3] * x[3] - x[0] + x[1] - x[2] + x[3] + 8.0;
    g[1] = -x[0] * x[0] - x[1] * x[1] * 2.0 - x[2] * x[2] - x[3] * x[3] * 2.0 + x[0] + x[3] + 10.0;
    g[2] = -x[0] * x[0] * 2.0 - x[1] * x[1] - x[2] * x[2] - x[0] * 2.0 + x[1] + x[3] + 5.0;
});
hs!(Hs44, f: |x| x[0] - x[1] - x[2] - x[0] * x[2] + x[0] * x[3] + x[1] * x[2] - x[1] * x[3],
g: |x, g| {
    g[0] = -x[0] - x[1] * 2.0 + 8.0;
    g[1] = -x[0] * 4.0 - x[1] + 12.0;
    g[2] = -x[0] * 3.0 - x[1] * 4.0 + 12.0;
    g[3] = -x[2] * 2.0 - x[3] + 8.0;
    g[4] = -x[2] - x[3] * 2.0 + 8.0;
    g[5] = -x[2] - x[3] + 5.0;
});
hs!(Hs45, f: |x| -x[0] * x[1] * x[2] * x[3] * x[4] / 120.0 + 2.0);
hs!(Hs46, f: |x| (x[0] - x[1]).powi(2) + (x[2] - 1.0).powi(2) + (x[3] - 1.0).powi(4) + (x[4] - 1.0).powi(6),
g: |x, g| {
    g[0] = x[0] * x[0] * x[3] + (x[3] - x[4]).sin() - 1.0;
    g[1] = x[1] + x[2].powi(4) * x[3] * x[3] - 2.0;
});
hs!(Hs47, f: |x| (x[0] - x[1]).powi(2) + (x[1] - x[2]).powi(3) + (x[2] - x[3]).powi(4) + (x[3] - x[4]).powi(4),
g: |x, g| {
    g[0] = x[0] + x[1] * x[1] + x[2].powi(3) - 3.0;
    g[1] = x[1] - x[2] * x[2] + x[3] - 1.0;
    g[2] = x[0] * x[4] - 1.0;
});
hs!(Hs48, f: |x| (x[0] - 1.0).powi(2) + (x[1] - x[2]).powi(2) + (x[3] - x[4]).powi(2),
g: |x, g| {
    g[0] = x[0] + x[1] + x[2] + x[3] + x[4] - 5.0;
    g[1] = x[2] - (x[3] + x[4]) * 2.0 + 3.0;
});
hs!(Hs49, f: |x| (x[0] - x[1]).powi(2) + (x[2] - 1.0).powi(2) + (x[3] - 1.0).powi(4) + (x[4] - 1.0).powi(6),
g: |x, g| {
    g[0] = x[0] + x[1] + x[2] + x[3] * 4.0 - 7.0;
    g[1] = x[2] + x[4] * 5.0 - 6.0;
});
hs!(Hs50, f: |x| (x[0] - x[1]).powi(2) + (x[1] - x[2]).powi(2) + (x[2] - x[3]).powi(4) + (x[3] - x[4]).powi(2),
g: |x, g| {
    g[0] = x[0] + x[1] * 2.0 + x[2] * 3.0 - 6.0;
    g[1] = x[1] + x[2] * 2.0 + x[3] * 3.0 - 6.0;
    g[2] = x[2] + x[3] * 2.0 + x[4] * 3.0 - 6.0;
});
hs!(Hs71, f: |x| x[0] * x[3] * (x[0] + x[1] + x[2]) + x[2],
g: |x, g| {
    g[0] = x[0] * x[1] * x[2] * x[3] - 25.0;
    g[1] = x[0] * x[0] + x[1] * x[1] + x[2] * x[2] + x[3] * x[3] - 40.0;
});
hs!(Hs76, f: |x| x[0] * x[0] + x[1] * x[1] * 0.5 + x[2] * x[2] + x[3] * x[3] * 0.5 - x[0] * x[2]
    + x[2] * x[3] - x[0] - x[1] * 3.0 + x[2] - x[3],
g: |x, g| {
    g[0] = -x[0] - x[1] * 2.0 - x[2] - x[3] + 5.0;
    g[1] = -x[0] * 3.0 - x[1] - x[2] * 2.0 + x[3] + 4.0;
    g[2] = x[1] + x[2] * 4.0 - 1.5;
});
hs!(Hs100, f: |x| (x[0] - 10.0).powi(2) + (x[1] - 12.0).powi(2) * 5.0 + x[2].powi(4)
    + (x[3] - 11.0).powi(2) * 3.0 + x[4].powi(6) * 10.0 + x[5] * x[5] * 7.0 + x[6].powi(4)
    - x[5] * x[6] * 4.0 - x[5] * 10.0 - x[6] * 8.0,
g: |x, g| {
    g[0] = -x[0] * x[0] * 2.0 - x[1].powi(4) * 3.0 - x[2] - x[3] * x[3] * 4.0 - x[4] * 5.0 + 127.0;
    g[1] = -x[0] * 7.0 - x[1] * 3.0 - x[2] * x[2] * 10.0 - x[3] + x[4] + 282.0;
    g[2] = -x[0] * 23.0 - x[1] * x[1] - x[5] * x[5] * 6.0 + x[6] * 8.0 + 196.0;
    g[3] = -x[0] * x[0] * 4.0 - x[1] * x[1] + x[0] * x[1] * 3.0 - x[2] * x[2] * 2.0 - x[5] * 5.0 + x[6] * 11.0;
});
fn hs104_objective<D: DualNum<Primitive = f64> + Copy>(x: &[D]) -> D {
    (x[0].powf(0.67) * x[6].powf(-0.67) + x[1].powf(0.67) * x[7].powf(-0.67)) * 0.4 - x[0] - x[1]
        + 10.0
}
hs!(Hs104, f: |x| hs104_objective(x),
g: |x, g| {
    g[0] = -x[4] * x[6] * 0.0588 - x[0] * 0.1 + 1.0;
    g[1] = -x[5] * x[7] * 0.0588 - x[0] * 0.1 - x[1] * 0.1 + 1.0;
    g[2] = -x[2] * x[4].recip() * 4.0 - x[2].powf(-0.71) * x[4].recip() * 2.0
        - x[2].powf(-1.3) * x[6] * 0.0588 + 1.0;
    g[3] = -x[3] * x[5].recip() * 4.0 - x[3].powf(-0.71) * x[5].recip() * 2.0
        - x[3].powf(-1.3) * x[7] * 0.0588 + 1.0;
    g[4] = hs104_objective(x);
});
hs!(Hs106, f: |x| x[0] + x[1] + x[2],
g: |x, g| {
    g[0] = -(x[3] + x[5]) * 0.0025 + 1.0;
    g[1] = -(x[4] + x[6] - x[3]) * 0.0025 + 1.0;
    g[2] = -(x[7] - x[4]) * 0.01 + 1.0;
    g[3] = x[0] * x[5] - x[3] * 833.33252 - x[0] * 100.0 + 83333.333;
    g[4] = x[1] * x[6] - x[4] * 1250.0 - x[1] * x[3] + x[3] * 1250.0;
    g[5] = x[2] * x[7] - x[2] * x[4] + x[4] * 2500.0 - 1_250_000.0;
});
hs!(Hs108, f: |x| (x[0] * x[3] - x[1] * x[2] + x[2] * x[8] - x[4] * x[8] + x[4] * x[7] - x[5] * x[6]) * -0.5,
g: |x, g| {
    g[0] = -x[2] * x[2] - x[3] * x[3] + 1.0;
    g[1] = -x[8] * x[8] + 1.0;
    g[2] = -x[4] * x[4] - x[5] * x[5] + 1.0;
    g[3] = -x[0] * x[0] - (x[1] - x[8]).powi(2) + 1.0;
    g[4] = -(x[0] - x[4]).powi(2) - (x[1] - x[5]).powi(2) + 1.0;
    g[5] = -(x[0] - x[6]).powi(2) - (x[1] - x[7]).powi(2) + 1.0;
    g[6] = -(x[2] - x[4]).powi(2) - (x[3] - x[5]).powi(2) + 1.0;
    g[7] = -(x[2] - x[6]).powi(2) - (x[3] - x[7]).powi(2) + 1.0;
    g[8] = -x[6] * x[6] - (x[7] - x[8]).powi(2) + 1.0;
    g[9] = x[0] * x[3] - x[1] * x[2];
    g[10] = x[2] * x[8];
    g[11] = -x[4] * x[8];
    g[12] = x[4] * x[7] - x[5] * x[6];
});
hs!(Hs116, f: |x| x[10] + x[11] + x[12],
g: |x, g| {
    let (a, b, c, d, e, f) = (0.002, 1.262626, 1.231059, 0.03475, 0.975, 0.00975);
    g[0] = x[2] - x[1];
    g[1] = x[1] - x[0];
    g[2] = -x[6] * a + x[7] * a + 1.0;
    g[3] = x[10] + x[11] + x[12] - 50.0;
    g[4] = -x[10] - x[11] - x[12] + 250.0;
    g[5] = x[12] - x[9] * b + x[2] * x[9] * c;
    g[6] = x[4] - x[1] * d - x[1] * x[4] * e + x[1] * x[1] * f;
    g[7] = x[5] - x[2] * d - x[2] * x[5] * e + x[2] * x[2] * f;
    g[8] = x[3] - x[0] * d - x[0] * x[3] * e + x[0] * x[0] * f;
    g[9] = x[11] - x[8] * b + x[1] * x[8] * c;
    g[10] = x[10] - x[7] * b + x[0] * x[7] * c;
    g[11] = x[4] * x[6] - x[0] * x[7] - x[3] * x[6] + x[3] * x[7];
    g[12] = -(x[1] * x[8] + x[4] * x[7] - x[0] * x[7] - x[5] * x[8]) * a - x[4] - x[5] + 1.0;
    g[13] = x[1] * x[8] - x[2] * x[9] - x[5] * x[8] - x[1] * 500.0 + x[5] * 500.0 + x[1] * x[9];
    g[14] = x[1] - (x[1] * x[9] - x[2] * x[9]) * a - 0.9;
});
hs!(Hs118, f: |x| {
    let mut sum = x[0] * 0.0;
    for k in 0..5 {
        let (p, q, r) = (x[3 * k], x[3 * k + 1], x[3 * k + 2]);
        sum += p * 2.3 + p * p * 0.0001 + q * 1.7 + q * q * 0.0001 + r * 2.2 + r * r * 0.00015;
    }
    sum
},
g: |x, g| {
    for j in 1..5 {
        for i in 0..3 {
            g[3 * (j - 1) + i] = x[3 * j + i] - x[3 * j + i - 3];
        }
    }
    for k in 0..5 {
        g[12 + k] = x[3 * k] + x[3 * k + 1] + x[3 * k + 2];
    }
});

fn all_rows() -> Vec<Row> {
    let sqrt3 = 3f64.sqrt();
    let mut rows = vec![
        run::<Hs1>(Spec::new("HS1", &[-2.0, 1.0], 0.0).bounds(&[-INF, -1.5], &[INF, INF])),
        run::<Hs1>(
            Spec::new("HS2", &[-2.0, 1.0], 0.050_426_187_9).bounds(&[-INF, 1.5], &[INF, INF]),
        ),
        run::<Hs3>(Spec::new("HS3", &[10.0, 1.0], 0.0).bounds(&[-INF, 0.0], &[INF, INF])),
        run::<Hs4>(Spec::new("HS4", &[1.125, 0.125], 8.0 / 3.0).bounds(&[1.0, 0.0], &[INF, INF])),
        run::<Hs5>(
            Spec::new("HS5", &[0.0, 0.0], -0.5 * sqrt3 - PI / 3.0)
                .bounds(&[-1.5, -3.0], &[4.0, 3.0]),
        ),
        run::<Hs6>(Spec::new("HS6", &[-1.2, 1.0], 0.0).eq(1)),
        run::<Hs7>(Spec::new("HS7", &[2.0, 2.0], -sqrt3).eq(1)),
        run::<Hs8>(Spec::new("HS8", &[2.0, 1.0], -1.0).eq(2)),
        run::<Hs9>(Spec::new("HS9", &[0.0, 0.0], -0.5).eq(1)),
        run::<Hs10>(Spec::new("HS10", &[-10.0, 10.0], -1.0).ge(1)),
        run::<Hs11>(Spec::new("HS11", &[4.9, 0.1], -8.498_464_223).ge(1)),
        run::<Hs12>(Spec::new("HS12", &[0.0, 0.0], -30.0).ge(1)),
        run::<Hs13>(
            Spec::new("HS13", &[-2.0, -2.0], 1.0)
                .bounds(&[0.0, 0.0], &[INF, INF])
                .ge(1),
        ),
        run::<Hs14>(
            Spec::new("HS14", &[2.0, 2.0], 9.0 - 2.875 * 7f64.sqrt())
                .ge(1)
                .eq(1),
        ),
        run::<Hs15>(
            Spec::new("HS15", &[-2.0, 1.0], 306.5)
                .bounds(&[-INF, -INF], &[0.5, INF])
                .ge(2),
        ),
        run::<Hs16>(
            Spec::new("HS16", &[-2.0, 1.0], 0.25)
                .bounds(&[-0.5, -INF], &[0.5, 1.0])
                .ge(2),
        ),
        run::<Hs17>(
            Spec::new("HS17", &[-2.0, 1.0], 1.0)
                .bounds(&[-0.5, -INF], &[0.5, 1.0])
                .ge(2),
        ),
        run::<Hs18>(
            Spec::new("HS18", &[2.0, 2.0], 5.0)
                .bounds(&[2.0, 0.0], &[50.0, 50.0])
                .ge(2),
        ),
        run::<Hs19>(
            Spec::new("HS19", &[20.1, 5.84], -6_961.813_875_580_15)
                .bounds(&[13.0, 0.0], &[100.0, 100.0])
                .ge(2),
        ),
        run::<Hs20>(
            Spec::new("HS20", &[-2.0, 1.0], 81.5 - 25.0 * sqrt3)
                .bounds(&[-0.5, -INF], &[0.5, INF])
                .ge(3),
        ),
        run::<Hs21>(
            Spec::new("HS21", &[-1.0, -1.0], -99.96)
                .bounds(&[2.0, -50.0], &[50.0, 50.0])
                .ge(1),
        ),
        run::<Hs22>(Spec::new("HS22", &[2.0, 2.0], 1.0).ge(2)),
        run::<Hs23>(
            Spec::new("HS23", &[3.0, 1.0], 2.0)
                .bounds(&[-50.0, -50.0], &[50.0, 50.0])
                .ge(5),
        ),
        run::<Hs24>(
            Spec::new("HS24", &[1.0, 0.5], -1.0)
                .bounds(&[0.0, 0.0], &[INF, INF])
                .ge(3),
        ),
        run::<Hs26>(Spec::new("HS26", &[-2.6, 2.0, 2.0], 0.0).eq(1)),
        run::<Hs27>(Spec::new("HS27", &[2.0, 2.0, 2.0], 0.04).eq(1)),
        run::<Hs28>(Spec::new("HS28", &[-4.0, 1.0, 1.0], 0.0).eq(1)),
        run::<Hs29>(Spec::new("HS29", &[1.0, 1.0, 1.0], -16.0 * 2f64.sqrt()).ge(1)),
        run::<Hs30>(
            Spec::new("HS30", &[1.0, 1.0, 1.0], 1.0)
                .bounds(&[1.0, -10.0, -10.0], &[10.0, 10.0, 10.0])
                .ge(1),
        ),
        run::<Hs31>(
            Spec::new("HS31", &[1.0, 1.0, 1.0], 6.0)
                .bounds(&[-10.0, 1.0, -10.0], &[10.0, 10.0, 1.0])
                .ge(1),
        ),
        run::<Hs32>(
            Spec::new("HS32", &[0.1, 0.7, 0.2], 1.0)
                .bounds(&[0.0; 3], &[INF; 3])
                .ge(1)
                .eq(1),
        ),
        run::<Hs33>(
            Spec::new("HS33", &[0.0, 0.0, 3.0], 2f64.sqrt() - 6.0)
                .bounds(&[0.0; 3], &[INF, INF, 5.0])
                .ge(2),
        ),
        run::<Hs34>(
            Spec::new("HS34", &[0.0, 1.05, 2.9], -(10f64.ln().ln()))
                .bounds(&[0.0; 3], &[100.0, 100.0, 10.0])
                .ge(2),
        ),
        run::<Hs35>(
            Spec::new("HS35", &[0.5; 3], 1.0 / 9.0)
                .bounds(&[0.0; 3], &[INF; 3])
                .ge(1),
        ),
        run::<Hs36>(
            Spec::new("HS36", &[10.0; 3], -3300.0)
                .bounds(&[0.0; 3], &[20.0, 11.0, 42.0])
                .ge(1),
        ),
        run::<Hs37>(
            Spec::new("HS37", &[10.0; 3], -3456.0)
                .bounds(&[0.0; 3], &[42.0; 3])
                .ge(2),
        ),
        run::<Hs38>(
            Spec::new("HS38", &[-3.0, -1.0, -3.0, -1.0], 0.0).bounds(&[-10.0; 4], &[10.0; 4]),
        ),
        run::<Hs39>(Spec::new("HS39", &[2.0; 4], -1.0).eq(2)),
        run::<Hs40>(Spec::new("HS40", &[0.8; 4], -0.25).eq(3)),
        run::<Hs41>(
            Spec::new("HS41", &[2.0; 4], 52.0 / 27.0)
                .bounds(&[0.0; 4], &[1.0, 1.0, 1.0, 2.0])
                .eq(1),
        ),
        run::<Hs42>(Spec::new("HS42", &[1.0; 4], 28.0 - 10.0 * 2f64.sqrt()).eq(2)),
        run::<Hs43>(Spec::new("HS43", &[0.0; 4], -44.0).ge(3)),
        run::<Hs44>(
            Spec::new("HS44", &[0.0; 4], -15.0)
                .bounds(&[0.0; 4], &[INF; 4])
                .ge(6),
        ),
        run::<Hs45>(
            Spec::new("HS45", &[2.0; 5], 1.0).bounds(&[0.0; 5], &[1.0, 2.0, 3.0, 4.0, 5.0]),
        ),
        run::<Hs46>(Spec::new("HS46", &[0.5 * 2f64.sqrt(), 1.75, 0.5, 2.0, 2.0], 0.0).eq(2)),
        run::<Hs47>(
            Spec::new(
                "HS47",
                &[2.0, 2f64.sqrt(), -1.0, 2.0 - 2f64.sqrt(), 0.5],
                0.0,
            )
            .eq(3),
        ),
        run::<Hs48>(Spec::new("HS48", &[3.0, 5.0, -3.0, 2.0, -2.0], 0.0).eq(2)),
        run::<Hs49>(Spec::new("HS49", &[10.0, 7.0, 2.0, -3.0, 0.8], 0.0).eq(2)),
        run::<Hs50>(Spec::new("HS50", &[35.0, -31.0, 11.0, 5.0, -5.0], 0.0).eq(3)),
        run::<Hs71>(
            Spec::new("HS71", &[1.0, 5.0, 5.0, 1.0], 17.014_017_3)
                .bounds(&[1.0; 4], &[5.0; 4])
                .ge(1)
                .eq(1),
        ),
        run::<Hs76>(
            Spec::new("HS76", &[0.5; 4], -4.681_818_181)
                .bounds(&[0.0; 4], &[INF; 4])
                .ge(3),
        ),
        run::<Hs100>(Spec::new("HS100", &[1.0, 2.0, 0.0, 4.0, 0.0, 1.0, 1.0], 680.630_057_3).ge(4)),
        run::<Hs104>(
            Spec::new(
                "HS104",
                &[6.0, 3.0, 0.4, 0.2, 6.0, 6.0, 1.0, 0.5],
                3.951_163_439_6,
            )
            .bounds(&[0.1; 8], &[10.0; 8])
            .ge(4)
            .range(1.0, 4.2),
        ),
        run::<Hs106>(
            Spec::new(
                "HS106",
                &[5000.0, 5000.0, 5000.0, 200.0, 350.0, 150.0, 225.0, 425.0],
                7_049.248_020_5,
            )
            .bounds(
                &[100.0, 1000.0, 1000.0, 10.0, 10.0, 10.0, 10.0, 10.0],
                &[
                    10000.0, 10000.0, 10000.0, 1000.0, 1000.0, 1000.0, 1000.0, 1000.0,
                ],
            )
            .ge(6),
        ),
        run::<Hs108>(
            Spec::new("HS108", &[1.0; 9], -0.866_025_403_8)
                .bounds(
                    &[-INF, -INF, -INF, -INF, -INF, -INF, -INF, -INF, 0.0],
                    &[INF; 9],
                )
                .ge(13),
        ),
        run::<Hs116>(
            Spec::new(
                "HS116",
                &[
                    0.5, 0.8, 0.9, 0.1, 0.14, 0.5, 489.0, 80.0, 650.0, 450.0, 150.0, 150.0, 150.0,
                ],
                97.588_409,
            )
            .bounds(
                &[
                    0.1, 0.1, 0.1, 0.0001, 0.1, 0.1, 0.1, 0.1, 500.0, 0.1, 1.0, 0.0001, 0.0001,
                ],
                &[
                    1.0, 1.0, 1.0, 0.1, 0.9, 0.9, 1000.0, 1000.0, 1000.0, 500.0, 150.0, 150.0,
                    150.0,
                ],
            )
            .ge(15),
        ),
    ];
    let mut hs118 = Spec::new(
        "HS118",
        &[
            20.0, 55.0, 15.0, 20.0, 60.0, 20.0, 20.0, 60.0, 20.0, 20.0, 60.0, 20.0, 20.0, 60.0,
            20.0,
        ],
        664.820_45,
    )
    .bounds(
        &[
            8.0, 43.0, 3.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
        ],
        &[
            21.0, 57.0, 16.0, 90.0, 120.0, 60.0, 90.0, 120.0, 60.0, 90.0, 120.0, 60.0, 90.0, 120.0,
            60.0,
        ],
    );
    for _ in 1..5 {
        hs118 = hs118.range(-7.0, 6.0).range(-7.0, 7.0).range(-7.0, 6.0);
    }
    for demand in [60.0, 50.0, 70.0, 85.0, 100.0] {
        hs118 = hs118.range(demand, INF);
    }
    rows.push(run::<Hs118>(hs118));
    rows
}

/// Solves every problem with `backend` and checks the outcome against `known` failures.
fn check_suite(backend: Backend, known: &[(&str, &str)]) {
    BACKEND.with(|b| b.set(backend));
    let rows = all_rows();
    println!(
        "{:<6} {:>3} {:>3} {:>5} {:>18} {:>18} {:>9} {:>8}  status",
        "name", "n", "m", "iter", "objective", "published", "rel.err", "infeas"
    );
    for row in &rows {
        println!(
            "{:<6} {:>3} {:>3} {:>5} {:>18.10e} {:>18.10e} {:>9.1e} {:>8.1e}  {}{}",
            row.name,
            row.n,
            row.m,
            row.iterations,
            row.objective,
            row.published,
            row.error,
            row.infeasibility,
            row.status,
            if row.passed { "" } else { "  FAIL" }
        );
    }
    let passed = rows.iter().filter(|row| row.passed).count();
    println!("{backend:?}: passed {passed} of {} problems", rows.len());

    assert!(rows.len() >= 30);
    let is_known = |name: &str| known.iter().any(|(k, _)| *k == name);
    let unexpected: Vec<_> = rows
        .iter()
        .filter(|row| !row.passed && !is_known(row.name))
        .map(|row| row.name)
        .collect();
    assert!(unexpected.is_empty(), "unexpected failures: {unexpected:?}");
    let fixed: Vec<_> = rows
        .iter()
        .filter(|row| row.passed && is_known(row.name))
        .map(|row| row.name)
        .collect();
    assert!(
        fixed.is_empty(),
        "known failures now pass, update KNOWN_FAILURES: {fixed:?}"
    );
}

#[test]
fn hock_schittkowski_problems_reach_their_published_optima() {
    check_suite(Backend::Ripopt, KNOWN_FAILURES);
}

#[test]
fn the_native_interior_point_reaches_the_same_optima() {
    check_suite(Backend::Native, KNOWN_FAILURES_NATIVE);
}
