//! Figures of the CLI, drawn with plotters into PNG and SVG. Text uses the DejaVu Sans font
//! embedded in the binary (assets/fonts), so no system font is needed.

use anyhow::{anyhow, Result};
use plotters::prelude::*;
use std::path::Path;
use std::sync::Once;

static FONT: &[u8] = include_bytes!("../assets/fonts/DejaVuSans.ttf");

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
    register_font()?;
    let png = prefix.with_extension("png");
    let svg = prefix.with_extension("svg");
    {
        let root = BitMapBackend::new(&png, (900, 800)).into_drawing_area();
        draw_convergence(&root, arrows, bounds_m, paper_m)?;
        root.present()
            .map_err(|e| anyhow!("{}: {e}", png.display()))?;
    }
    {
        let root = SVGBackend::new(&svg, (900, 800)).into_drawing_area();
        draw_convergence(&root, arrows, bounds_m, paper_m)?;
        root.present()
            .map_err(|e| anyhow!("{}: {e}", svg.display()))?;
    }
    Ok(())
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
    let err = |e: DrawingAreaErrorKind<DB::ErrorType>| anyhow!("drawing: {e:?}");
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
