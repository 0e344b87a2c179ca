//! `worley tune`: Worley's density tuning, measured. For each density λ (and
//! bump of low populations), per order: the SIMD kernel's speed in exact
//! mode, the wrong-rate of the window-only search, the share of samples the
//! exact search must widen, and the statistics of F1.

use std::path::PathBuf;
use std::time::Instant;

use worley::{Config, Mode, Outputs, Reference, Simd};
use worley_harness::{self as harness, sample_point, Campaign, Report};

/// Options of `worley tune`.
#[derive(clap::Args, Debug)]
pub struct TuneArgs {
    /// Dimension: 2, 3 or 4.
    #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u8).range(2..=4))]
    pub dim: u8,
    /// Densities λ to sweep, comma-separated.
    #[arg(long, default_value = "1,1.5,2,2.5,3,4,5,6,8")]
    pub densities: String,
    /// Orders n to report, comma-separated (1, 2, 4 or 8).
    #[arg(long, default_value = "1,2,4")]
    pub orders: String,
    /// Bumps of the 0/1 populations to sweep, comma-separated (Worley's
    /// tuning; 0 is the plain Poisson table).
    #[arg(long, default_value = "0")]
    pub bumps: String,
    /// Samples checked against brute force per setting and mode.
    #[arg(long, default_value_t = 200_000)]
    pub oracle_samples: usize,
    /// Points timed per setting and order (median of seven runs in
    /// interleaved rounds, one thread).
    #[arg(long, default_value_t = 1 << 17)]
    pub speed_samples: usize,
    /// Samples and cells for the statistics (KS, grid bias).
    #[arg(long, default_value_t = 200_000)]
    pub statistics_samples: usize,
    /// Folder for tune.json and tune.svg.
    #[arg(long, default_value = "out")]
    pub out: PathBuf,
}

/// One measured setting.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Row {
    /// Density λ.
    pub density: f64,
    /// Bump fraction.
    pub bump: f64,
    /// Order n.
    pub order: usize,
    /// SIMD kernel, exact mode, F1..Fn distances, M samples/s on one
    /// thread: the median of seven runs, taken in rounds over all settings.
    pub simd_mps: f64,
    /// The slowest and fastest of the seven runs.
    pub simd_mps_spread: (f64, f64),
    /// Share of samples whose F_n is wrong with the 3^d window only.
    pub window_wrong: f64,
    /// Share of samples the exact search widens beyond the 3^d block.
    pub widened: f64,
    /// KS distance of F1 from the Poisson law.
    pub ks: f64,
    /// Grid bias of F1 (centre against corner of cells).
    pub grid_bias: f64,
    /// Whether no other setting of the same order dominates this one: none
    /// is clearly faster (its slowest run beats this one's fastest) with no
    /// more window error, and none has less window error at a median speed
    /// at least as high.
    pub on_front: bool,
    /// This order's median speed as a share of the fastest median of the
    /// same order among the settings swept.
    pub share_of_best: f64,
    /// Whether this setting (λ and bump, all orders together) is on the
    /// joint front: one density serves every order, so a setting is
    /// dominated only by one that is clearly faster at every order swept
    /// with no more window error at any of them.
    pub joint_front: bool,
}

impl Row {
    /// The setting this row measures (λ and bump), comparable exactly.
    fn setting(&self) -> (u64, u64) {
        (self.density.to_bits(), self.bump.to_bits())
    }
}

/// Runs of the speed measurement per setting and order.
const RUNS: usize = 7;

/// One timed pass of the 8-lane kernel over `points`: returns M samples/s.
type Timer<'a> = Box<dyn FnMut() -> f64 + 'a>;

fn timer<'a, const D: usize, const N: usize>(config: Config, points: &'a [[f64; D]]) -> Result<Timer<'a>, String> {
    let kernel = Simd::<D, N>::new(Config { order: N, ..config }, Outputs::Distances).map_err(|e| e.to_string())?;
    let mut out =
        vec![worley::Features32::<D, N> { distance: [0.0; N], delta: [[0.0; D]; N], id: [0; N] }; points.len()];
    Ok(Box::new(move || {
        let t = Instant::now();
        // The length matches by construction, so this cannot fail.
        let _ = kernel.evaluate_slice(points, &mut out);
        std::hint::black_box(&out);
        points.len() as f64 / t.elapsed().as_secs_f64() / 1e6
    }))
}

fn timer_of<'a, const D: usize>(config: Config, points: &'a [[f64; D]]) -> Result<Timer<'a>, String> {
    match config.order {
        1 => timer::<D, 1>(config, points),
        2 => timer::<D, 2>(config, points),
        4 => timer::<D, 4>(config, points),
        8 => timer::<D, 8>(config, points),
        n => Err(format!("order {n} is not swept: use 1, 2, 4 or 8")),
    }
}

fn oracle<const D: usize>(config: Config, campaign: &Campaign) -> Result<Report, String> {
    let kernel = Reference::<D>::new(config).map_err(|e| e.to_string())?;
    let mut report = Report::new::<D>("reference".into(), &config, kernel.pattern(), campaign);
    harness::compare_with_oracle(&kernel, campaign, &mut report);
    Ok(report)
}

fn statistics<const D: usize>(config: Config, campaign: &Campaign) -> Result<(f64, f64), String> {
    let kernel = Reference::<D>::new(config).map_err(|e| e.to_string())?;
    let mut report = Report::new::<D>("reference".into(), &config, kernel.pattern(), campaign);
    harness::throughput_and_statistics(&kernel, campaign, &mut report);
    Ok((report.ks, harness::grid_bias(&kernel, campaign)))
}

fn sweep<const D: usize>(
    args: &TuneArgs,
    densities: &[f64],
    orders: &[usize],
    bumps: &[f64],
) -> Result<Vec<Row>, String> {
    let settings = densities.len() * bumps.len();
    let bar = crate::commands::progress((settings * (1 + RUNS * orders.len())) as u64, "steps");
    let mut rows = Vec::new();
    let top = *orders.iter().max().unwrap_or(&1);
    for &bump in bumps {
        for &density in densities {
            let base = Config { density, bump, ..Config::default() };
            let stats = Campaign {
                samples: args.statistics_samples,
                oracle_samples: 0,
                pairs: 0,
                grid_cells: args.statistics_samples,
                ..Campaign::default()
            };
            let (ks, grid_bias) = statistics::<D>(base, &stats)?;
            bar.inc(1);
            let check = Campaign {
                samples: 0,
                oracle_samples: args.oracle_samples,
                pairs: 0,
                grid_cells: 0,
                ..Campaign::default()
            };
            let exact = oracle::<D>(Config { order: top, ..base }, &check)?;
            let window = oracle::<D>(Config { order: top, mode: Mode::Window, ..base }, &check)?;
            for &order in orders {
                let share = |n: u64| n as f64 / args.oracle_samples.max(1) as f64;
                rows.push(Row {
                    density,
                    bump,
                    order,
                    simd_mps: 0.0,
                    simd_mps_spread: (0.0, 0.0),
                    window_wrong: share(window.orders[order - 1].oracle_disagreements),
                    // Widening for F_n is measured by the reference at the
                    // sweep's top order: it records per order whether F_k
                    // needed cells beyond the 3^d block.
                    widened: share(exact.orders[order - 1].needs_wider),
                    ks,
                    grid_bias,
                    on_front: false,
                    share_of_best: 0.0,
                    joint_front: false,
                });
            }
        }
    }
    // Speed in rounds: each round times every setting once, so a slow spell
    // of a shared machine falls on all settings alike instead of on the few
    // measured during it.
    let points: Vec<[f64; D]> = (0..args.speed_samples).map(|i| sample_point(7, i, 1000.0)).collect();
    let mut timers = Vec::with_capacity(rows.len());
    for r in &rows {
        timers.push(timer_of::<D>(
            Config { density: r.density, bump: r.bump, order: r.order, ..Config::default() },
            &points,
        )?);
    }
    let mut runs = vec![[0f64; RUNS]; rows.len()];
    for round in 0..RUNS {
        for (t, r) in timers.iter_mut().zip(runs.iter_mut()) {
            r[round] = t();
            bar.inc(1);
        }
    }
    for (row, mut r) in rows.iter_mut().zip(runs) {
        r.sort_by(f64::total_cmp);
        row.simd_mps = r[RUNS / 2];
        row.simd_mps_spread = (r[0], r[RUNS - 1]);
    }
    bar.finish_and_clear();
    for i in 0..rows.len() {
        let r = &rows[i];
        let dominated = rows.iter().any(|o| {
            o.order == r.order
                && ((o.window_wrong <= r.window_wrong && o.simd_mps_spread.0 > r.simd_mps_spread.1)
                    || (o.window_wrong < r.window_wrong && o.simd_mps >= r.simd_mps))
        });
        let best = rows.iter().filter(|o| o.order == r.order).map(|o| o.simd_mps).fold(0.0, f64::max);
        rows[i].on_front = !dominated;
        rows[i].share_of_best = if best > 0.0 { rows[i].simd_mps / best } else { 0.0 };
    }
    for i in 0..rows.len() {
        let r = &rows[i];
        let dominated = rows.iter().any(|o| {
            o.setting() != r.setting()
                && rows.iter().filter(|x| x.setting() == r.setting()).all(|x| {
                    rows.iter().any(|y| {
                        y.setting() == o.setting()
                            && y.order == x.order
                            && y.window_wrong <= x.window_wrong
                            && y.simd_mps_spread.0 > x.simd_mps_spread.1
                    })
                })
        });
        rows[i].joint_front = !dominated;
    }
    Ok(rows)
}

/// `worley tune`.
pub fn tune(args: &TuneArgs) -> Result<(), String> {
    let densities: Vec<f64> = crate::commands::parse_list(&args.densities, "density")?;
    let bumps: Vec<f64> = crate::commands::parse_list(&args.bumps, "bump")?;
    let orders: Vec<usize> = crate::commands::parse_list(&args.orders, "order")?;
    if let Some(n) = orders.iter().find(|n| ![1, 2, 4, 8].contains(*n)) {
        return Err(format!("order {n} is not swept: use 1, 2, 4 or 8"));
    }
    for &density in &densities {
        for &bump in &bumps {
            Config { density, bump, ..Config::default() }.validate().map_err(|e| e.to_string())?;
        }
    }
    let started = Instant::now();
    let rows = match args.dim {
        2 => sweep::<2>(args, &densities, &orders, &bumps)?,
        3 => sweep::<3>(args, &densities, &orders, &bumps)?,
        _ => sweep::<4>(args, &densities, &orders, &bumps)?,
    };
    println!(
        "density sweep, {}D, seed 0, Euclidean; SIMD speed on one thread ({}), exact mode;",
        args.dim,
        worley::simd_level()
    );
    println!("window wrong-rate and widened share over {} samples against brute force;", args.oracle_samples);
    println!("on the front: no setting of the same order is clearly faster (slowest run above this one's fastest) with no more error, or has less error at a median speed at least as high");
    println!(
        "{:>6} {:>5} {:>5} | {:>9} {:>13} {:>6} | {:>12} {:>9} | {:>8} {:>9} | {:>5}",
        "λ", "bump", "order", "SIMD M/s", "(runs)", "share", "window wrong", "widened", "KS", "grid bias", "front"
    );
    for r in &rows {
        let default = r.density == worley::config::DEFAULT_DENSITY && r.bump == 0.0;
        println!(
            "{:>6} {:>5} {:>5} | {:>9.2} {:>13} {:>6.3} | {:>11.4}% {:>8.3}% | {:>8.5} {:>8.3}% | {:>5}{}",
            r.density,
            r.bump,
            format!("F{}", r.order),
            r.simd_mps,
            format!("{:.2}-{:.2}", r.simd_mps_spread.0, r.simd_mps_spread.1),
            r.share_of_best,
            100.0 * r.window_wrong,
            100.0 * r.widened,
            r.ks,
            100.0 * r.grid_bias,
            if r.on_front { "yes" } else { "no" },
            if default { "  <- default" } else { "" }
        );
    }
    println!("\nper setting, all orders together (share: the worst order's median over that order's fastest median;");
    println!("joint front: no other setting is clearly faster at every order with no more window error at any)");
    println!("{:>6} {:>5} | {:>12} {:>6} | {:>11}", "λ", "bump", "worst share", "order", "joint front");
    let mut seen = Vec::new();
    for r in &rows {
        if seen.contains(&r.setting()) {
            continue;
        }
        seen.push(r.setting());
        let same = rows.iter().filter(|o| o.setting() == r.setting());
        let worst = same.min_by(|a, b| a.share_of_best.total_cmp(&b.share_of_best)).unwrap_or(r);
        let default = r.density == worley::config::DEFAULT_DENSITY && r.bump == 0.0;
        println!(
            "{:>6} {:>5} | {:>12.3} {:>6} | {:>11}{}",
            r.density,
            r.bump,
            worst.share_of_best,
            format!("F{}", worst.order),
            if r.joint_front { "yes" } else { "no" },
            if default { "  <- default" } else { "" }
        );
    }
    std::fs::create_dir_all(&args.out).map_err(|e| format!("cannot create {}: {e}", args.out.display()))?;
    let json = serde_json::to_string_pretty(&rows).map_err(|e| e.to_string())?;
    let (json_path, svg_path) = (args.out.join("tune.json"), args.out.join("tune.svg"));
    crate::picture::write_output(&json_path, json.as_bytes())?;
    crate::picture::write_output(&svg_path, plot(&rows, args.dim)?.as_bytes())?;
    println!("\nwrote {} and {} ({:.1} s)", json_path.display(), svg_path.display(), started.elapsed().as_secs_f64());
    Ok(())
}

/// Speed against window wrong-rate (log scale), a line per order and bump,
/// each point labelled with its λ; filled points are on their order's
/// front, bold labels on the joint front, and the default is ringed.
///
/// # Errors
/// The plotting library's message, should drawing fail.
pub fn plot(rows: &[Row], dim: u8) -> Result<String, String> {
    use plotters::prelude::*;
    let fail = |e: &dyn std::fmt::Display| format!("cannot draw the plot: {e}");
    // Wrong-rates below the floor (often exactly 0) are drawn at the floor.
    let floor = 1e-5;
    let x_of = |r: &Row| r.window_wrong.max(floor);
    let x_hi = rows.iter().map(x_of).fold(1e-2, f64::max) * 3.0;
    let y_hi = rows.iter().map(|r| r.simd_mps).fold(1.0, f64::max) * 1.15;
    let colours = [RGBColor(192, 57, 43), RGBColor(36, 113, 163), RGBColor(34, 153, 84), RGBColor(125, 60, 152)];
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (760, 480)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| fail(&e))?;
        let mut chart = ChartBuilder::on(&root)
            .caption(format!("{dim}D: SIMD speed (exact) against window-only error, per density λ"), ("sans-serif", 16))
            .margin(12)
            .x_label_area_size(44)
            .y_label_area_size(56)
            .build_cartesian_2d((floor..x_hi).log_scale(), 0.0..y_hi)
            .map_err(|e| fail(&e))?;
        chart
            .configure_mesh()
            .x_desc("share of samples with a wrong F_n, 3^d window only (below 0.001 % drawn at 0.001 %)")
            .y_desc("M samples/s, one thread")
            .x_label_formatter(&|v| format!("{}%", 100.0 * v))
            .draw()
            .map_err(|e| fail(&e))?;
        let mut series: Vec<(usize, f64)> = rows.iter().map(|r| (r.order, r.bump)).collect();
        series.sort_by(|a, b| a.partial_cmp(b).unwrap_or(std::cmp::Ordering::Equal));
        series.dedup();
        for (s, &(order, bump)) in series.iter().enumerate() {
            let colour = colours[s % colours.len()];
            let points: Vec<&Row> = rows.iter().filter(|r| r.order == order && r.bump == bump).collect();
            let label = if bump == 0.0 { format!("F{order}") } else { format!("F{order}, bump {bump}") };
            chart
                .draw_series(LineSeries::new(points.iter().map(|r| (x_of(r), r.simd_mps)), colour))
                .map_err(|e| fail(&e))?
                .label(label)
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], colour.stroke_width(2)));
            let style = |r: &Row| if r.on_front { colour.filled() } else { colour.stroke_width(1) };
            chart
                .draw_series(points.iter().map(|r| Circle::new((x_of(r), r.simd_mps), 4, style(r))))
                .map_err(|e| fail(&e))?;
            chart
                .draw_series(points.iter().map(|r| {
                    let font = ("sans-serif", 11).into_font();
                    let font = if r.joint_front { font.style(FontStyle::Bold) } else { font };
                    Text::new(format!("{}", r.density), (x_of(r), r.simd_mps), font)
                }))
                .map_err(|e| fail(&e))?;
            chart
                .draw_series(
                    points
                        .iter()
                        .filter(|r| r.density == worley::config::DEFAULT_DENSITY && r.bump == 0.0)
                        .map(|r| Circle::new((x_of(r), r.simd_mps), 9, BLACK.stroke_width(2))),
                )
                .map_err(|e| fail(&e))?;
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperRight)
            .background_style(WHITE)
            .border_style(BLACK)
            .draw()
            .map_err(|e| fail(&e))?;
        root.draw(&Text::new(
            "ringed: default λ; filled: on its order's front; bold λ: on the joint front",
            (80, 40),
            ("sans-serif", 11),
        ))
        .map_err(|e| fail(&e))?;
        root.present().map_err(|e| fail(&e))?;
    }
    Ok(svg)
}
