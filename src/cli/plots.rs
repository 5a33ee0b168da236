//! Figures of the CLI, drawn with plotters into PNG and SVG. Text uses the DejaVu Sans font
//! embedded in the binary (assets/fonts), so no system font is needed.

use anyhow::{anyhow, Result};
use plotters::prelude::*;
use runtime::telemetry::speed_read::SpeedRow;
use std::path::Path;
use std::sync::Once;

static FONT: &[u8] = include_bytes!("../../assets/fonts/DejaVuSans.ttf");

/// Registers the embedded font as plotters' "sans-serif" (once per process).
fn register_font() -> Result<()> {
    static REGISTER: Once = Once::new();
    let mut result = Ok(());
    REGISTER.call_once(|| {
        if plotters::style::register_font("sans-serif", FontStyle::Normal, FONT).is_err() {
            result = Err(anyhow!("the embedded DejaVu Sans font did not load"));
        }
    });
    result
}

/// Draws `$draw(&root, args…)` into `<prefix>.png` and `<prefix>.svg` of `$size` pixels (the
/// same drawing code on both backends) and returns `Ok(())`.
macro_rules! png_and_svg {
    ($prefix:expr, $size:expr, $draw:ident($($arg:expr),*)) => {{
        register_font()?;
        let png = $prefix.with_extension("png");
        let svg = $prefix.with_extension("svg");
        {
            let root = BitMapBackend::new(&png, $size).into_drawing_area();
            $draw(&root, $($arg),*)?;
            root.present()
                .map_err(|e| anyhow!("{}: {e}", png.display()))?;
        }
        {
            let root = SVGBackend::new(&svg, $size).into_drawing_area();
            $draw(&root, $($arg),*)?;
            root.present()
                .map_err(|e| anyhow!("{}: {e}", svg.display()))?;
        }
        Ok(())
    }};
}

/// One arrow of the convergence figure: initial → converged (thigh, shin), m, and whether the
/// run ended in a worse local minimum.
pub struct ConvergenceArrow {
    /// Initial (thigh, shin), m.
    pub from_m: (f64, f64),
    /// Converged (thigh, shin), m.
    pub to_m: (f64, f64),
    /// A worse local minimum.
    pub local_minimum: bool,
}

/// The paper's Fig. 3: initial → converged thigh and shin lengths of the convergence study, as
/// `<prefix>.png` and `<prefix>.svg`.
pub fn convergence(
    prefix: &Path,
    arrows: &[ConvergenceArrow],
    bounds_m: [[f64; 2]; 2],
    paper_m: (f64, f64),
) -> Result<()> {
    png_and_svg!(
        prefix,
        (900, 800),
        draw_convergence(arrows, bounds_m, paper_m)
    )
}

fn draw_convergence<DB: DrawingBackend>(
    root: &DrawingArea<DB, plotters::coord::Shift>,
    arrows: &[ConvergenceArrow],
    bounds_m: [[f64; 2]; 2],
    paper_m: (f64, f64),
) -> Result<()>
where
    DB::ErrorType: 'static,
{
    let err = |e: DrawingAreaErrorKind<DB::ErrorType>| anyhow!("drawing: {e}");
    root.fill(&WHITE).map_err(err)?;
    let pad = 0.01;
    let mut chart = ChartBuilder::on(root)
        .caption(
            "Co-design convergence: initial → converged lengths",
            ("sans-serif", 24),
        )
        .margin(20)
        .x_label_area_size(50)
        .y_label_area_size(60)
        .build_cartesian_2d(
            (bounds_m[0][0] - pad)..(bounds_m[0][1] + pad),
            (bounds_m[1][0] - pad)..(bounds_m[1][1] + pad),
        )
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc("thigh length (m)")
        .y_desc("shin length (m)")
        .label_style(("sans-serif", 16))
        .axis_desc_style(("sans-serif", 18))
        .draw()
        .map_err(err)?;
    let good = RGBColor(31, 119, 180);
    let bad = RGBColor(214, 39, 40);
    for (local_minimum, color, label) in [
        (false, good, "initial design (open) → converged (filled)"),
        (true, bad, "run ended in a worse local minimum"),
    ] {
        let set: Vec<&ConvergenceArrow> = arrows
            .iter()
            .filter(|a| a.local_minimum == local_minimum)
            .collect();
        if set.is_empty() {
            continue;
        }
        for a in &set {
            chart
                .draw_series(LineSeries::new([a.from_m, a.to_m], color.stroke_width(1)))
                .map_err(err)?;
            chart
                .draw_series([Circle::new(a.from_m, 4, color.stroke_width(1))])
                .map_err(err)?;
        }
        chart
            .draw_series(set.iter().map(|a| Circle::new(a.to_m, 5, color.filled())))
            .map_err(err)?
            .label(label)
            .legend(move |(x, y)| Circle::new((x + 10, y), 5, color.filled()));
    }
    chart
        .draw_series([Cross::new(paper_m, 8, BLACK.stroke_width(2))])
        .map_err(err)?
        .label("paper's optimum (0.2425, 0.2515) m")
        .legend(|(x, y)| Cross::new((x + 10, y), 6, BLACK.stroke_width(2)));
    chart
        .configure_series_labels()
        .label_font(("sans-serif", 15))
        .background_style(WHITE.mix(0.9))
        .border_style(BLACK)
        .position(SeriesLabelPosition::LowerRight)
        .draw()
        .map_err(err)?;
    Ok(())
}

/// One run in a phase portrait: its label and its joint series.
pub struct PortraitRun<'a> {
    /// Legend label.
    pub label: String,
    /// The series.
    pub series: &'a runtime::telemetry::log_read::JointSeries,
}

/// The paper's Fig. 4: phase portraits (q vs q̇) of the left and right hip and knee, one panel
/// per joint, every run overlaid, as `<prefix>.png` and `<prefix>.svg`.
pub fn portraits(prefix: &Path, runs: &[PortraitRun<'_>]) -> Result<()> {
    png_and_svg!(prefix, (1200, 900), draw_portraits(runs))
}

fn draw_portraits<DB: DrawingBackend>(
    root: &DrawingArea<DB, plotters::coord::Shift>,
    runs: &[PortraitRun<'_>],
) -> Result<()>
where
    DB::ErrorType: 'static,
{
    let err = |e: DrawingAreaErrorKind<DB::ErrorType>| anyhow!("drawing: {e}");
    root.fill(&WHITE).map_err(err)?;
    let colors = [
        RGBColor(31, 119, 180),
        RGBColor(214, 39, 40),
        RGBColor(44, 160, 44),
        RGBColor(148, 103, 189),
    ];
    let titles = [
        "left hip pitch",
        "left knee pitch",
        "right hip pitch",
        "right knee pitch",
    ];
    let panels = root.split_evenly((2, 2));
    // Panel order: left hip, right hip / left knee, right knee.
    for (panel, &joint) in panels.iter().zip(&[0usize, 2, 1, 3]) {
        let (mut qmin, mut qmax, mut vmin, mut vmax) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
        for r in runs {
            for (&q, &v) in r.series.q_rad[joint].iter().zip(&r.series.dq_rad_s[joint]) {
                qmin = qmin.min(q);
                qmax = qmax.max(q);
                vmin = vmin.min(v);
                vmax = vmax.max(v);
            }
        }
        let (pq, pv) = (
            0.05 * (qmax - qmin).max(1e-3),
            0.05 * (vmax - vmin).max(1e-3),
        );
        let mut chart = ChartBuilder::on(panel)
            .caption(titles[joint], ("sans-serif", 20))
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(55)
            .build_cartesian_2d((qmin - pq)..(qmax + pq), (vmin - pv)..(vmax + pv))
            .map_err(err)?;
        chart
            .configure_mesh()
            .x_desc("q (rad)")
            .y_desc("dq/dt (rad/s)")
            .label_style(("sans-serif", 13))
            .axis_desc_style(("sans-serif", 15))
            .draw()
            .map_err(err)?;
        for (i, r) in runs.iter().enumerate() {
            let color = colors[i % colors.len()];
            let points = r.series.q_rad[joint]
                .iter()
                .copied()
                .zip(r.series.dq_rad_s[joint].iter().copied());
            chart
                .draw_series(LineSeries::new(points, color.stroke_width(1)))
                .map_err(err)?
                .label(r.label.clone())
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2))
                });
        }
        chart
            .configure_series_labels()
            .label_font(("sans-serif", 13))
            .background_style(WHITE.mix(0.9))
            .border_style(BLACK)
            .position(SeriesLabelPosition::UpperRight)
            .draw()
            .map_err(err)?;
    }
    Ok(())
}

/// The paper's Fig. 5: stick figures of one step at evenly spaced phases, side by side, as
/// `<prefix>.png` and `<prefix>.svg`; `source` names the log in the caption.
pub fn tiles(prefix: &Path, tiles: &runtime::tiles::GaitTiles, source: &str) -> Result<()> {
    png_and_svg!(prefix, tiles_size(tiles), draw_tiles(tiles, source))
}

/// Horizontal distance between tiles, and the x and z ranges of the figure, m.
fn tiles_frame(tiles: &runtime::tiles::GaitTiles) -> (f64, (f64, f64), (f64, f64)) {
    let (mut xmin, mut xmax, mut zmax) = (0.0f64, 0.0f64, 0.0f64);
    for f in &tiles.figures {
        for p in f
            .torso_m
            .iter()
            .chain(&f.stance_leg_m)
            .chain(&f.swing_leg_m)
        {
            xmin = xmin.min(p[0]);
            xmax = xmax.max(p[0]);
            zmax = zmax.max(p[1]);
        }
    }
    let spacing = (xmax - xmin) + 0.15;
    let n = tiles.figures.len() as f64;
    // Room on the right for the legend.
    (
        spacing,
        (
            xmin - 0.08,
            xmin + (n - 1.0) * spacing + (xmax - xmin) + 0.45,
        ),
        (-0.06, zmax + 0.12),
    )
}

fn tiles_size(tiles: &runtime::tiles::GaitTiles) -> (u32, u32) {
    let (_, x, z) = tiles_frame(tiles);
    // Equal scale on both axes: the plot area is 480 px tall, plus margins and labels.
    let px_per_m = 480.0 / (z.1 - z.0);
    (((x.1 - x.0) * px_per_m) as u32 + 110, 480 + 130)
}

fn draw_tiles<DB: DrawingBackend>(
    root: &DrawingArea<DB, plotters::coord::Shift>,
    tiles: &runtime::tiles::GaitTiles,
    source: &str,
) -> Result<()>
where
    DB::ErrorType: 'static,
{
    let err = |e: DrawingAreaErrorKind<DB::ErrorType>| anyhow!("drawing: {e}");
    root.fill(&WHITE).map_err(err)?;
    let (spacing, x, z) = tiles_frame(tiles);
    let caption = format!(
        "Gait tiles: {} (thigh {:.3} m, shin {:.3} m), step {} of {}: {:.3} m in {:.3} s",
        tiles.robot,
        tiles.design_m.0,
        tiles.design_m.1,
        tiles.step,
        source,
        tiles.step_length_m,
        tiles.step_duration_s
    );
    let mut chart = ChartBuilder::on(root)
        .caption(caption, ("sans-serif", 16))
        .margin(15)
        .x_label_area_size(40)
        .y_label_area_size(50)
        .build_cartesian_2d(x.0..x.1, z.0..z.1)
        .map_err(err)?;
    chart
        .configure_mesh()
        .disable_x_mesh()
        .disable_y_mesh()
        .x_desc("x (m), each tile offset by its index")
        .y_desc("z (m)")
        .label_style(("sans-serif", 12))
        .axis_desc_style(("sans-serif", 14))
        .draw()
        .map_err(err)?;
    chart
        .draw_series(LineSeries::new([(x.0, 0.0), (x.1, 0.0)], BLACK.mix(0.5)))
        .map_err(err)?;
    let stance_color = RGBColor(31, 119, 180);
    let swing_color = RGBColor(214, 39, 40);
    let torso_color = RGBColor(60, 60, 60);
    for (k, f) in tiles.figures.iter().enumerate() {
        let dx = k as f64 * spacing;
        let at = |p: &[f64; 2]| (p[0] + dx, p[1]);
        for (points, color, label) in [
            (&f.swing_leg_m[..], swing_color, "swing leg"),
            (&f.torso_m[..], torso_color, "torso"),
            (&f.stance_leg_m[..], stance_color, "stance leg"),
        ] {
            let series = chart
                .draw_series(LineSeries::new(
                    points.iter().map(at),
                    color.stroke_width(4),
                ))
                .map_err(err)?;
            if k == 0 {
                series.label(label).legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(4))
                });
            }
            chart
                .draw_series(points.iter().map(|p| Circle::new(at(p), 3, color.filled())))
                .map_err(err)?;
        }
        let top = f.torso_m[1][1].max(f.torso_m[0][1]);
        chart
            .draw_series([Text::new(
                format!("τ = {:.2}", f.phase),
                (f.torso_m[0][0] + dx - 0.06, top + 0.08),
                ("sans-serif", 14),
            )])
            .map_err(err)?;
    }
    chart
        .configure_series_labels()
        .label_font(("sans-serif", 13))
        .background_style(WHITE.mix(0.9))
        .border_style(BLACK)
        .position(SeriesLabelPosition::LowerRight)
        .draw()
        .map_err(err)?;
    Ok(())
}

/// `adam plot speed`: speeds (belt, commanded, measured per step, library gait) over position
/// on the belt (estimated, and true where the simulator logged it) against time, as
/// `<prefix>.png` and `<prefix>.svg`.
pub fn speed(prefix: &Path, rows: &[SpeedRow], source: &str) -> Result<()> {
    png_and_svg!(prefix, (1000, 800), draw_speed(rows, source))
}

fn draw_speed<DB: DrawingBackend>(
    root: &DrawingArea<DB, plotters::coord::Shift>,
    rows: &[SpeedRow],
    source: &str,
) -> Result<()>
where
    DB::ErrorType: 'static,
{
    root.fill(&WHITE).map_err(|e| anyhow!("drawing: {e}"))?;
    let (top, bottom) = root.split_vertically(420);
    let t0 = rows.first().map_or(0.0, |r| r.t_s).min(0.0);
    let t1 = rows.last().map_or(1.0, |r| r.t_s).max(t0 + 1.0);
    let speeds: [(&str, RGBColor, SpeedPick); 4] = [
        ("belt (set)", RGBColor(0, 0, 0), |r| r.belt_mps),
        ("commanded", RGBColor(31, 119, 180), |r| r.commanded_mps),
        ("measured step speed", RGBColor(214, 39, 40), |r| {
            r.step_speed_mps
        }),
        ("library gait in use", RGBColor(44, 160, 44), |r| {
            r.library_mps
        }),
    ];
    let (lo, hi) = finite_values(rows, &speeds)
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v), b.max(v))
        });
    let (lo, hi) = if lo.is_finite() {
        (lo - 0.02, hi + 0.02)
    } else {
        (0.0, 0.5)
    };
    speed_panel(
        &top,
        Some(format!("Treadmill speed control: {source}")),
        (t0..t1, lo..hi),
        "speed (m/s)",
        &speeds,
        rows,
    )?;
    let positions: [(&str, RGBColor, SpeedPick); 2] = [
        ("estimated (leg odometry)", RGBColor(31, 119, 180), |r| {
            r.position_m
        }),
        ("true (simulator)", RGBColor(0, 0, 0), |r| r.true_position_m),
    ];
    let extent = finite_values(rows, &positions).fold(0.1_f64, |a, v| a.max(v.abs())) + 0.02;
    speed_panel(
        &bottom,
        None,
        (t0..t1, -extent..extent),
        "position on the belt (m, + forward)",
        &positions,
        rows,
    )
}

/// One `/speed` field of a row.
type SpeedPick = fn(&SpeedRow) -> f64;

/// The finite values of `series` over `rows`.
fn finite_values<'a>(
    rows: &'a [SpeedRow],
    series: &'a [(&str, RGBColor, SpeedPick)],
) -> impl Iterator<Item = f64> + 'a {
    rows.iter()
        .flat_map(move |r| series.iter().map(move |s| (s.2)(r)))
        .filter(|v| v.is_finite())
}

/// One panel of `adam plot speed`: `series` (label, colour, field) against time, a line each
/// through its finite values (a series with none is left out of the legend).
fn speed_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    caption: Option<String>,
    (t, y): (std::ops::Range<f64>, std::ops::Range<f64>),
    y_desc: &str,
    series: &[(&str, RGBColor, SpeedPick)],
    rows: &[SpeedRow],
) -> Result<()>
where
    DB::ErrorType: 'static,
{
    let err = |e: DrawingAreaErrorKind<DB::ErrorType>| anyhow!("drawing: {e}");
    let mut builder = ChartBuilder::on(area);
    if let Some(caption) = caption {
        builder.caption(caption, ("sans-serif", 22));
    }
    let mut chart = builder
        .margin(15)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d(t, y)
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc("time (s)")
        .y_desc(y_desc)
        .label_style(("sans-serif", 15))
        .axis_desc_style(("sans-serif", 17))
        .draw()
        .map_err(err)?;
    for &(label, color, pick) in series {
        let points: Vec<(f64, f64)> = rows
            .iter()
            .map(|r| (r.t_s, pick(r)))
            .filter(|p| p.1.is_finite())
            .collect();
        if points.is_empty() {
            continue;
        }
        chart
            .draw_series(LineSeries::new(points, color.stroke_width(2)))
            .map_err(err)?
            .label(label)
            .legend(move |(x, y)| PathElement::new([(x, y), (x + 20, y)], color.stroke_width(2)));
    }
    chart
        .configure_series_labels()
        .label_font(("sans-serif", 14))
        .background_style(WHITE.mix(0.9))
        .border_style(BLACK)
        .draw()
        .map_err(err)?;
    Ok(())
}

/// The cost landscape over the design box: the optimal cost of a fixed-design gait at every
/// grid point, with the co-design optimum and the convergence study's endpoints on it.
pub struct HeatMap<'a> {
    /// The grid's thigh lengths (x), m.
    pub thigh_m: &'a [f64],
    /// The grid's shin lengths (y), m.
    pub shin_m: &'a [f64],
    /// Cost at point (i, j) at `i * shin_m.len() + j` (thigh-major); `None` where the solve
    /// failed (drawn grey).
    pub cost: &'a [Option<f64>],
    /// What the colour is (the colour bar's label).
    pub cost_label: &'a str,
    /// The co-design optimum (thigh, shin), m.
    pub optimum_m: Option<(f64, f64)>,
    /// The convergence study's endpoints (thigh, shin), m.
    pub sweep_ends_m: &'a [(f64, f64)],
}

/// Draws the [`HeatMap`] as `<prefix>.png` and `<prefix>.svg`.
pub fn landscape(prefix: &Path, map: &HeatMap<'_>) -> Result<()> {
    png_and_svg!(prefix, (1000, 800), draw_landscape(map))
}

fn draw_landscape<DB: DrawingBackend>(
    root: &DrawingArea<DB, plotters::coord::Shift>,
    map: &HeatMap<'_>,
) -> Result<()>
where
    DB::ErrorType: 'static,
{
    let err = |e: DrawingAreaErrorKind<DB::ErrorType>| anyhow!("drawing: {e}");
    root.fill(&WHITE).map_err(err)?;
    let (xs, ys) = (map.thigh_m, map.shin_m);
    if xs.len() < 2 || ys.len() < 2 || map.cost.len() != xs.len() * ys.len() {
        return Err(anyhow!(
            "a landscape figure needs a grid of at least 2 × 2 costs"
        ));
    }
    let finite = map.cost.iter().flatten().copied();
    let lo = finite.clone().fold(f64::INFINITY, f64::min);
    let hi = finite.fold(f64::NEG_INFINITY, f64::max);
    let (lo, hi) = if lo.is_finite() && hi > lo {
        (lo, hi)
    } else {
        (0.0, 1.0)
    };
    let (dx, dy) = (xs[1] - xs[0], ys[1] - ys[0]);
    let (plot, bar) = root.split_horizontally(860);
    let mut chart = ChartBuilder::on(&plot)
        .caption(
            "Optimal cost at fixed designs, co-design optimum and sweep endpoints",
            ("sans-serif", 20),
        )
        .margin(15)
        .x_label_area_size(50)
        .y_label_area_size(60)
        .build_cartesian_2d(
            (xs[0] - dx / 2.0)..(xs[xs.len() - 1] + dx / 2.0),
            (ys[0] - dy / 2.0)..(ys[ys.len() - 1] + dy / 2.0),
        )
        .map_err(err)?;
    chart
        .configure_mesh()
        .disable_mesh()
        .x_desc("thigh length (m)")
        .y_desc("shin length (m)")
        .label_style(("sans-serif", 16))
        .axis_desc_style(("sans-serif", 18))
        .draw()
        .map_err(err)?;
    let colour = |c: f64| viridis((c - lo) / (hi - lo));
    let grey = RGBColor(190, 190, 190);
    let cells = xs.iter().enumerate().flat_map(|(i, &x)| {
        ys.iter().enumerate().map(move |(j, &y)| {
            let fill = match map.cost[i * ys.len() + j] {
                Some(c) => colour(c),
                None => grey,
            };
            Rectangle::new(
                [(x - dx / 2.0, y - dy / 2.0), (x + dx / 2.0, y + dy / 2.0)],
                fill.filled(),
            )
        })
    });
    chart.draw_series(cells).map_err(err)?;
    let red = RGBColor(214, 39, 40);
    if !map.sweep_ends_m.is_empty() {
        chart
            .draw_series(
                map.sweep_ends_m
                    .iter()
                    .map(|&p| Circle::new(p, 6, WHITE.stroke_width(2))),
            )
            .map_err(err)?
            .label(format!(
                "convergence study: {} endpoints",
                map.sweep_ends_m.len()
            ))
            .legend(|(x, y)| Circle::new((x + 10, y), 6, BLACK.stroke_width(2)));
    }
    if let Some(o) = map.optimum_m {
        chart
            .draw_series([Cross::new(o, 10, red.stroke_width(3))])
            .map_err(err)?
            .label(format!("co-design optimum ({:.4}, {:.4}) m", o.0, o.1))
            .legend(move |(x, y)| Cross::new((x + 10, y), 7, red.stroke_width(3)));
    }
    chart
        .configure_series_labels()
        .label_font(("sans-serif", 15))
        .background_style(WHITE.mix(0.9))
        .border_style(BLACK)
        .position(SeriesLabelPosition::LowerLeft)
        .draw()
        .map_err(err)?;
    // The colour bar.
    let mut scale = ChartBuilder::on(&bar)
        .margin_top(60)
        .margin_bottom(65)
        .margin_right(10)
        .y_label_area_size(80)
        .build_cartesian_2d(0.0..1.0, lo..hi)
        .map_err(err)?;
    scale
        .configure_mesh()
        .disable_mesh()
        .disable_x_axis()
        .y_desc(map.cost_label)
        .y_label_formatter(&|v| format!("{v:.4}"))
        .label_style(("sans-serif", 14))
        .axis_desc_style(("sans-serif", 16))
        .draw()
        .map_err(err)?;
    let steps = 100;
    scale
        .draw_series((0..steps).map(|k| {
            let a = lo + (hi - lo) * k as f64 / steps as f64;
            let b = lo + (hi - lo) * (k + 1) as f64 / steps as f64;
            Rectangle::new([(0.0, a), (1.0, b)], colour(0.5 * (a + b)).filled())
        }))
        .map_err(err)?;
    Ok(())
}

/// Matplotlib's viridis at t ∈ [0, 1] (dark blue, low → yellow, high), linear between nine of
/// its samples (plotters' colour maps are behind a feature this build leaves out).
fn viridis(t: f64) -> RGBColor {
    const SAMPLES: [(u8, u8, u8); 9] = [
        (68, 1, 84),
        (71, 44, 122),
        (59, 81, 139),
        (44, 113, 142),
        (33, 144, 141),
        (39, 173, 129),
        (92, 200, 99),
        (170, 220, 50),
        (253, 231, 37),
    ];
    let x = t.clamp(0.0, 1.0) * (SAMPLES.len() - 1) as f64;
    let k = (x.floor() as usize).min(SAMPLES.len() - 2);
    let f = x - k as f64;
    let mix = |a: u8, b: u8| (a as f64 + (b as f64 - a as f64) * f).round() as u8;
    let (a, b) = (SAMPLES[k], SAMPLES[k + 1]);
    RGBColor(mix(a.0, b.0), mix(a.1, b.1), mix(a.2, b.2))
}
