//! Shared plotting: the embedded font (no system fonts needed), rendering a
//! figure to PNG and SVG atomically, colour maps and colour bars, and the
//! log10 axes every figure shares (decades labelled 10ᵏ, minor lines at 2..9).

pub mod case;
pub mod matrix;

use plotters::coord::combinators::{BindKeyPoints, WithKeyPoints};
use plotters::coord::ranged1d::{KeyPointHint, NoDefaultFormatting, ValueFormatter};
use plotters::coord::types::RangedCoordf64;
use plotters::coord::{CoordTranslate, Shift};
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use plotters::style::FontStyle;
use std::ops::Range;
use std::path::Path;
use study::output::files::write_atomic;

pub type Res<T = ()> = Result<T, String>;

const FONT: &[u8] = include_bytes!("../../../../../assets/fonts/DejaVuSans.ttf");
pub const SANS: &str = "sans-serif";

pub fn err<E: std::fmt::Debug>(e: E) -> String {
    format!("{e:?}")
}

/// Registers the embedded DejaVu Sans once per process.
pub fn fonts() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        for style in [FontStyle::Normal, FontStyle::Bold] {
            if plotters::style::register_font(SANS, style, FONT).is_err() {
                panic!("the embedded DejaVu Sans does not parse");
            }
        }
    });
}

/// A figure drawable on any backend.
pub trait Figure {
    fn size(&self) -> (u32, u32);
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Res;
}

/// Writes `stem`.png and `stem`.svg into `dir`; returns the two file names.
pub fn render(fig: &impl Figure, dir: &Path, stem: &str) -> Res<[String; 2]> {
    fonts();
    std::fs::create_dir_all(dir).map_err(err)?;
    let (png, svg) = (format!("{stem}.png"), format!("{stem}.svg"));
    let tmp = dir.join(format!(".{stem}.tmp{}.png", std::process::id()));
    {
        let root = BitMapBackend::new(&tmp, fig.size()).into_drawing_area();
        root.fill(&WHITE).map_err(err)?;
        fig.draw(&root)?;
        root.present().map_err(err)?;
    }
    std::fs::rename(&tmp, dir.join(&png)).map_err(err)?;
    let mut text = String::new();
    {
        let root = SVGBackend::with_string(&mut text, fig.size()).into_drawing_area();
        root.fill(&WHITE).map_err(err)?;
        fig.draw(&root)?;
        root.present().map_err(err)?;
    }
    write_atomic(&dir.join(&svg), text.as_bytes()).map_err(err)?;
    Ok([png, svg])
}

/// Draws `title` centred at the top of `area`, wrapped at spaces into as
/// many lines as the width needs (a plotters caption is one line and is
/// clipped at the figure's edges); returns the height it took, in pixels.
pub fn draw_title<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    title: &str,
    size: u32,
) -> Res<u32> {
    if title.trim().is_empty() {
        return Ok(0);
    }
    let style = TextStyle::from((SANS, size).into_font()).pos(Pos::new(HPos::Center, VPos::Top));
    let (w, _) = area.dim_in_pixel();
    let room = w.saturating_sub(2 * TITLE_SIDE);
    let width = |s: &str| {
        area.estimate_text_size(s, &style)
            .map(|(x, _)| x)
            .unwrap_or(u32::MAX)
    };
    let lines = wrap_words(title, room, width);
    let line_h = size + size / 4;
    for (k, line) in lines.iter().enumerate() {
        let y = TITLE_TOP + line_h * k as u32;
        area.draw(&Text::new(
            line.clone(),
            ((w / 2) as i32, y as i32),
            style.clone(),
        ))
        .map_err(err)?;
    }
    Ok(TITLE_TOP + line_h * lines.len() as u32)
}

/// Pixels kept clear beside and above a title.
const TITLE_SIDE: u32 = 10;
const TITLE_TOP: u32 = 4;

/// `area` below its wrapped title (the counterpart of plotters' `titled`).
pub fn titled<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    title: &str,
    size: u32,
) -> Res<DrawingArea<DB, Shift>> {
    let h = draw_title(area, title, size)?;
    Ok(area.margin(h + if h > 0 { 6 } else { 0 }, 0, 0, 0))
}

/// Greedy word wrap: each line as long as fits `room` by `width`; a single
/// word wider than `room` stands alone on its line.
pub fn wrap_words(text: &str, room: u32, width: impl Fn(&str) -> u32) -> Vec<String> {
    let mut lines: Vec<String> = vec![];
    for word in text.split_whitespace() {
        match lines.last_mut() {
            Some(line) if width(&format!("{line} {word}")) <= room => {
                line.push(' ');
                line.push_str(word);
            }
            _ => lines.push(word.to_string()),
        }
    }
    lines
}

/// Viridis, interpolated between 6 stops; s in [0, 1].
pub fn viridis(s: f64) -> RGBColor {
    const STOPS: [(u8, u8, u8); 6] = [
        (68, 1, 84),
        (65, 68, 135),
        (42, 120, 142),
        (34, 168, 132),
        (122, 209, 81),
        (253, 231, 37),
    ];
    let s = if s.is_finite() {
        s.clamp(0.0, 1.0)
    } else {
        0.0
    } * (STOPS.len() - 1) as f64;
    let k = (s.floor() as usize).min(STOPS.len() - 2);
    let f = s - k as f64;
    let mix = |a: u8, b: u8| (a as f64 + f * (b as f64 - a as f64)).round() as u8;
    let (a, b) = (STOPS[k], STOPS[k + 1]);
    RGBColor(mix(a.0, b.0), mix(a.1, b.1), mix(a.2, b.2))
}

/// A scalar range mapped to colours, linear or log10.
#[derive(Clone, Copy, Debug)]
pub struct ColourScale {
    pub lo: f64,
    pub hi: f64,
    pub log: bool,
}

impl ColourScale {
    /// From the 1st to the 99th percentile of the finite values (log: of the positive ones).
    pub fn robust(values: &[f64], log: bool) -> Self {
        let mut v: Vec<f64> = values
            .iter()
            .copied()
            .filter(|x| x.is_finite() && (!log || *x > 0.0))
            .collect();
        if v.is_empty() {
            return ColourScale {
                lo: if log { 1e-3 } else { 0.0 },
                hi: 1.0,
                log,
            };
        }
        v.sort_by(f64::total_cmp);
        let q = |f: f64| v[((v.len() - 1) as f64 * f).round() as usize];
        let (mut lo, mut hi) = (q(0.01), q(0.99));
        if hi <= lo {
            hi = if log { lo * 10.0 } else { lo + 1.0 };
        }
        if log {
            lo = lo.max(hi * 1e-8);
        }
        ColourScale { lo, hi, log }
    }

    pub fn unit(&self, x: f64) -> f64 {
        if self.log {
            let (a, b) = (self.lo.log10(), self.hi.log10());
            (x.max(self.lo * 1e-3).log10() - a) / (b - a)
        } else {
            (x - self.lo) / (self.hi - self.lo)
        }
    }

    pub fn colour(&self, x: f64) -> RGBColor {
        viridis(self.unit(x))
    }
}

/// A vertical colour bar with its label; a log scale gets a log axis
/// (decades labelled, minor ticks at 2..9), widened to hold a decade if it
/// must be, the colours beyond the scale's ends then saturated as on the map.
pub fn colour_bar<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    scale: &ColourScale,
    label: &str,
) -> Res {
    if scale.log {
        let (a, b) = (scale.lo.log10(), scale.hi.log10());
        let axis = LogAxis::new(a, b);
        let (lo, hi) = (axis.range().start, axis.range().end);
        let minors = axis.minors().to_vec();
        let mut chart = bar_builder(area)
            .build_cartesian_2d(0.0..1.0, axis)
            .map_err(err)?;
        let fmt = |v: &f64| log_label(v);
        bar_body(&mut chart, (lo, hi), label, &fmt, |y| (y - a) / (b - a))?;
        chart
            .draw_series(
                minors
                    .iter()
                    .map(|&m| PathElement::new([(0.0, m), (0.18, m)], BLACK.mix(0.7))),
            )
            .map_err(err)?;
    } else {
        let (lo, hi) = (scale.lo, scale.hi);
        let mut chart = bar_builder(area)
            .build_cartesian_2d(0.0..1.0, lo..hi)
            .map_err(err)?;
        let fmt = |v: &f64| short(*v);
        bar_body(&mut chart, (lo, hi), label, &fmt, |y| (y - lo) / (hi - lo))?;
    }
    Ok(())
}

fn bar_builder<'a, 'b, DB: DrawingBackend>(
    area: &'a DrawingArea<DB, Shift>,
) -> ChartBuilder<'a, 'b, DB> {
    let mut b = ChartBuilder::on(area);
    b.margin_top(20)
        .margin_bottom(40)
        .margin_right(8)
        .y_label_area_size(62);
    b
}

/// The colour bar's axis and its 64 colour steps; `unit` maps a y to [0, 1].
fn bar_body<DB, Y>(
    chart: &mut ChartContext<'_, DB, Cartesian2d<RangedCoordf64, Y>>,
    (lo, hi): (f64, f64),
    label: &str,
    fmt: &dyn Fn(&f64) -> String,
    unit: impl Fn(f64) -> f64,
) -> Res
where
    DB: DrawingBackend,
    Y: Ranged<ValueType = f64> + ValueFormatter<f64>,
{
    chart
        .configure_mesh()
        .disable_x_mesh()
        .disable_y_mesh()
        .disable_x_axis()
        .y_desc(label)
        .y_label_formatter(fmt)
        .y_labels(6)
        .label_style((SANS, 13))
        .axis_desc_style((SANS, 14))
        .draw()
        .map_err(err)?;
    let n = 64;
    chart
        .draw_series((0..n).map(|k| {
            let a = lo + (hi - lo) * k as f64 / n as f64;
            let b = lo + (hi - lo) * (k + 1) as f64 / n as f64;
            Rectangle::new([(0.0, a), (1.0, b)], viridis(unit(0.5 * (a + b))).filled())
        }))
        .map_err(err)?;
    Ok(())
}

/// A log10 axis: the values are log10 of the data; whole decades are the
/// labelled key points (see [`decade_label`], its default formatter), the
/// points log10(2..9) + k between them the light mesh lines. Built on
/// plotters' `with_key_points`, wrapped because plotters gives
/// `WithKeyPoints<RangedCoordf64>` no label formatter, so a mesh could not
/// be drawn on it.
pub struct LogAxis(WithKeyPoints<RangedCoordf64>);

impl LogAxis {
    /// The axis over `lo..hi` (log10 values), widened by [`log_range`] to
    /// hold at least one whole decade.
    pub fn new(lo: f64, hi: f64) -> Self {
        let (lo, hi) = log_range(lo, hi);
        LogAxis(
            (lo..hi)
                .with_key_points(log_ticks(lo, hi))
                .with_light_points(log_minors(lo, hi)),
        )
    }

    /// The labelled decades (the tests read the axis back).
    #[cfg(test)]
    pub fn decades(&self) -> &[f64] {
        self.0.bold_points()
    }

    /// The minor points between the decades.
    pub fn minors(&self) -> &[f64] {
        self.0.light_points()
    }
}

impl Ranged for LogAxis {
    type ValueType = f64;
    type FormatOption = NoDefaultFormatting;

    fn range(&self) -> Range<f64> {
        self.0.range()
    }

    fn map(&self, value: &f64, limit: (i32, i32)) -> i32 {
        self.0.map(value, limit)
    }

    fn key_points<H: KeyPointHint>(&self, hint: H) -> Vec<f64> {
        self.0.key_points(hint)
    }

    fn axis_pixel_range(&self, limit: (i32, i32)) -> Range<i32> {
        self.0.axis_pixel_range(limit)
    }
}

impl ValueFormatter<f64> for LogAxis {
    fn format(value: &f64) -> String {
        log_label(value)
    }
}

/// `lo..hi` (log10 values) widened to floor..ceil when it holds no whole
/// decade or fewer than two of [`log_ticks`], so a log axis always has two
/// labelled ticks; a non-finite range
/// becomes 0..1 and a single whole decade k the range k-1..k+1.
pub fn log_range(lo: f64, hi: f64) -> (f64, f64) {
    if !(lo.is_finite() && hi.is_finite()) {
        return (0.0, 1.0);
    }
    let (lo, hi) = (lo.min(hi), lo.max(hi));
    let k = lo.round();
    if hi - lo < LOG_EPS && (lo - k).abs() < LOG_EPS {
        return (k - 1.0, k + 1.0);
    }
    if log_decades(lo, hi).is_empty() || log_ticks(lo, hi).len() < 2 {
        (lo.floor(), hi.ceil())
    } else {
        (lo, hi)
    }
}

/// Slack so that a decade at an end of the range, computed in floating
/// point, still counts as inside.
const LOG_EPS: f64 = 1e-9;

/// The whole decades k (as log10 values) inside `lo..=hi`.
pub fn log_decades(lo: f64, hi: f64) -> Vec<f64> {
    if !(lo.is_finite() && hi.is_finite()) {
        return vec![];
    }
    let (a, b) = ((lo - LOG_EPS).ceil() as i64, (hi + LOG_EPS).floor() as i64);
    (a..=b).map(|k| k as f64).collect()
}

/// The labelled points of a log axis: its whole decades, and 2 and 5 times
/// each decade as well when fewer than two decades fall inside, so that
/// every log axis and colour bar has at least two labelled ticks.
pub fn log_ticks(lo: f64, hi: f64) -> Vec<f64> {
    let decades = log_decades(lo, hi);
    if decades.len() >= 2 {
        return decades;
    }
    let mut ticks: Vec<f64> = (lo.floor() as i64..=hi.floor() as i64)
        .flat_map(|k| [1.0, 2.0, 5.0].map(|m: f64| k as f64 + m.log10()))
        .filter(|v| (lo - LOG_EPS..=hi + LOG_EPS).contains(v))
        .collect();
    ticks.sort_by(f64::total_cmp);
    ticks
}

/// The label of a log axis's tick: "10ᵏ" for a whole decade, the plain
/// number for 2 or 5 times one ("2", "0.5"), empty for anything else.
pub fn log_label(v: &f64) -> String {
    let decade = decade_label(v);
    if !decade.is_empty() || !v.is_finite() {
        return decade;
    }
    let mantissa = 10f64.powf(v - v.floor());
    if [2.0, 5.0].iter().any(|m| (mantissa - m).abs() < 1e-6) {
        short(10f64.powf(*v))
    } else {
        String::new()
    }
}

/// The minor points k + log10(m), m = 2..9, inside `lo..=hi` (log10 values).
pub fn log_minors(lo: f64, hi: f64) -> Vec<f64> {
    if !(lo.is_finite() && hi.is_finite()) {
        return vec![];
    }
    let (a, b) = (lo.floor() as i64, hi.floor() as i64);
    (a..=b)
        .flat_map(|k| (2..=9).map(move |m| k as f64 + (m as f64).log10()))
        .filter(|v| (lo - LOG_EPS..=hi + LOG_EPS).contains(v))
        .collect()
}

/// The label of a log10 value: "10ᵏ" with superscript digits for a whole
/// decade k ("10⁰", "10³", "10⁻²"), empty for anything else.
pub fn decade_label(v: &f64) -> String {
    let k = v.round();
    if !v.is_finite() || (v - k).abs() > 1e-6 {
        return String::new();
    }
    const SUP: [char; 10] = ['⁰', '¹', '²', '³', '⁴', '⁵', '⁶', '⁷', '⁸', '⁹'];
    let exp: String = format!("{}", k as i64)
        .chars()
        .map(|c| match c {
            '-' => '⁻',
            d => SUP[d.to_digit(10).unwrap_or(0) as usize],
        })
        .collect();
    format!("10{exp}")
}

/// The series legend every figure uses: framed, on a light background.
pub fn legend<'a, DB, CT>(
    chart: &mut ChartContext<'a, DB, CT>,
    position: SeriesLabelPosition,
    font_size: u32,
) -> Res
where
    DB: DrawingBackend + 'a,
    CT: CoordTranslate,
{
    chart
        .configure_series_labels()
        .position(position)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK.mix(0.3))
        .label_font((SANS, font_size))
        .draw()
        .map_err(err)
}

/// Compact number: 3 significant digits, exponent when large or small.
pub fn short(v: f64) -> String {
    let a = v.abs();
    if a != 0.0 && !(1e-2..1e4).contains(&a) {
        format!("{v:.1e}")
    } else {
        let s = format!("{v:.3}");
        let s = s.trim_end_matches('0').trim_end_matches('.');
        if s == "-0" {
            "0".into()
        } else {
            s.to_string()
        }
    }
}

/// Distinct line colours.
pub fn series_colour(k: usize) -> RGBColor {
    const C: [RGBColor; 8] = [
        RGBColor(31, 119, 180),
        RGBColor(255, 127, 14),
        RGBColor(44, 160, 44),
        RGBColor(214, 39, 40),
        RGBColor(148, 103, 189),
        RGBColor(140, 86, 75),
        RGBColor(227, 119, 194),
        RGBColor(127, 127, 127),
    ];
    C[k % C.len()]
}

#[cfg(test)]
mod tests;
