//! The `worley` command: the main job (the harness on the default
//! configuration and the image gallery), `worley check` (the harness on any
//! configuration), `worley render` (one image, or a window of it, as PNG,
//! PFM and EXR), `worley stitch` (windows into the whole EXR), `worley tune`
//! (the density sweep) and `worley ranges` (the combinations' output ranges).

use std::path::Path;
use std::process::ExitCode;

use clap::{Parser, Subcommand, ValueEnum};
use worley::{Config, Metric, Mode};
use worley_cli::commands::{parse_metric, ranges, RangesArgs};
use worley_cli::picture;
use worley_cli::render_cmd::{render_command, RenderArgs};
use worley_cli::runs::{run_reference, run_simd};
use worley_cli::tune::{tune, TuneArgs};
use worley_harness::{Campaign, Report};

#[derive(Parser)]
#[command(name = "worley", version, about = "Worley's cellular basis: harness and tools")]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
}

#[derive(Subcommand)]
enum Command {
    /// Run the harness on one configuration and print its report.
    Check(CheckArgs),
    /// Render one image, or a window of it (PNG, the raw values as PFM, and
    /// the channels as OpenEXR).
    Render(Box<RenderArgs>),
    /// Sweep the population density: speed against error per order.
    Tune(TuneArgs),
    /// Measure the output ranges of the standard combinations (the
    /// constants in `worley::texture::DEFAULT_RANGES`).
    Ranges(RangesArgs),
    /// Write only the image gallery of the main job.
    Gallery(GalleryArgs),
    /// Assemble the EXR files of `render --tile` or `--region` into the
    /// whole image.
    Stitch(StitchArgs),
}

#[derive(clap::Args)]
struct StitchArgs {
    /// The whole image to write (`-`: standard output).
    #[arg(long)]
    out: std::path::PathBuf,
    /// The windows' EXR files, in any order.
    #[arg(required = true)]
    inputs: Vec<std::path::PathBuf>,
}

#[derive(clap::Args)]
struct GalleryArgs {
    /// Folder for the images.
    #[arg(long, default_value = "out/gallery")]
    out: std::path::PathBuf,
    /// Pixels per tile (figures of several tiles are larger).
    #[arg(long, default_value_t = 384, value_parser = clap::value_parser!(u32).range(16..=4096))]
    tile: u32,
    /// Also write each figure's raw values as an EXR beside its PNG.
    #[arg(long)]
    exr: bool,
}

#[derive(Clone, Copy, PartialEq, ValueEnum)]
enum KernelArg {
    /// The f64 reference kernel.
    Reference,
    /// The 8-lane f32 kernel (orders 1, 2, 4 and 8).
    Simd,
}

#[derive(Clone, Copy, ValueEnum)]
enum ModeArg {
    Exact,
    Window,
}

#[derive(clap::Args)]
struct CheckArgs {
    /// Dimension: 2, 3 or 4.
    #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u8).range(2..=4))]
    dim: u8,
    /// Order n: F1..Fn are computed (1 to 16).
    #[arg(long, default_value_t = 1)]
    order: usize,
    /// Metric: euclidean, manhattan, chebyshev, or minkowski:P with P >= 1.
    #[arg(long, default_value = "euclidean", value_parser = parse_metric)]
    metric: Metric,
    /// Implementation under test.
    #[arg(long, value_enum, default_value_t = KernelArg::Reference)]
    kernel: KernelArg,
    /// Search mode.
    #[arg(long, value_enum, default_value_t = ModeArg::Exact)]
    mode: ModeArg,
    /// Pattern seed.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Mean density λ of the population table (points per cell).
    #[arg(long, default_value_t = worley::config::DEFAULT_DENSITY)]
    density: f64,
    /// Fraction of 0/1 populations bumped by one (Worley's tuning).
    #[arg(long, default_value_t = 0.0)]
    bump: f64,
    /// Random samples (throughput and statistics).
    #[arg(long, default_value_t = 1_000_000)]
    samples: usize,
    /// Samples checked against the brute-force oracle.
    #[arg(long, default_value_t = 200_000)]
    oracle_samples: usize,
    /// Straddling pairs for the continuity check.
    #[arg(long, default_value_t = 200_000)]
    pairs: usize,
    /// Cells for the grid bias, drawn from [-range, range]^d: with fewer
    /// distinct cells there than this (about 2·10^5 in 2D at the default
    /// range and λ), the bias is that one region's; the main job uses a
    /// range of 10^4.
    #[arg(long, default_value_t = 1_000_000)]
    grid_cells: usize,
    /// Samples are uniform in [-range, range]^d.
    #[arg(long, default_value_t = 1000.0)]
    range: f64,
    /// Seed of the sample generator.
    #[arg(long, default_value_t = 1)]
    campaign_seed: u64,
    /// Print JSON instead of the table.
    #[arg(long)]
    json: bool,
}

/// A command-line error as one line on standard error and exit code 2
/// (help and version go to standard output with exit code 0).
fn usage_error(e: &clap::Error) -> ExitCode {
    use clap::error::ErrorKind;
    if matches!(e.kind(), ErrorKind::DisplayHelp | ErrorKind::DisplayVersion) {
        let _ = e.print();
        return ExitCode::SUCCESS;
    }
    let text = e.to_string();
    let parts: Vec<&str> = text
        .lines()
        .map(str::trim)
        .filter(|l| !l.is_empty() && !l.starts_with("Usage:") && !l.starts_with("For more information"))
        .collect();
    let mut line = parts.join("; ");
    if let Some(rest) = line.strip_prefix("error: ") {
        line = rest.to_string();
    }
    if matches!(e.kind(), ErrorKind::UnknownArgument | ErrorKind::InvalidSubcommand) {
        line += "; see `worley --help` or `worley <command> --help` for what is accepted";
    }
    eprintln!("worley: {line}");
    ExitCode::from(2)
}

fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => return usage_error(&e),
    };
    let result = match cli.command {
        None => main_job(),
        Some(Command::Check(args)) => check(&args),
        Some(Command::Render(args)) => render_command(&args),
        Some(Command::Tune(args)) => tune(&args),
        Some(Command::Ranges(args)) => ranges(&args),
        Some(Command::Stitch(args)) => worley_cli::bake::stitch(&args.inputs, &args.out).map(|line| {
            if args.out.as_os_str() == "-" {
                eprintln!("{line}");
            } else {
                println!("{line}");
            }
        }),
        Some(Command::Gallery(args)) => worley_cli::gallery::gallery(&args.out, args.tile as usize, true, args.exr)
            .map(|written| {
                for path in written {
                    println!("{}", path.display());
                }
            }),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(message) => {
            eprintln!("worley: {message}");
            ExitCode::from(2)
        }
    }
}

fn check(args: &CheckArgs) -> Result<(), String> {
    let config = Config {
        seed: args.seed,
        order: args.order,
        metric: args.metric,
        mode: match args.mode {
            ModeArg::Exact => Mode::Exact,
            ModeArg::Window => Mode::Window,
        },
        density: args.density,
        bump: args.bump,
    };
    if !(args.range.is_finite() && args.range > 0.0) {
        return Err(format!("range {} is invalid: use a positive finite number", args.range));
    }
    let campaign = Campaign {
        seed: args.campaign_seed,
        samples: args.samples,
        oracle_samples: args.oracle_samples,
        range: args.range,
        pairs: args.pairs,
        grid_cells: args.grid_cells,
    };
    let spinner = indicatif::ProgressBar::new_spinner().with_message("running the campaign");
    spinner.enable_steady_tick(std::time::Duration::from_millis(200));
    let report = match args.kernel {
        KernelArg::Reference => run_reference(args.dim as usize, config, &campaign)?,
        KernelArg::Simd => run_simd(args.dim as usize, config, &campaign)?,
    };
    spinner.finish_and_clear();
    if args.json {
        println!("{}", report.to_json());
    } else {
        print!("{}", report.to_table());
    }
    Ok(())
}

/// The main job: for 2D, 3D and 4D, the reference's speed for F1, F2 and F4,
/// the reference and the SIMD kernel side by side (speed and error), the
/// exact and window searches against the oracle for orders 1..8, and the
/// statistics of F1. Prints four tables; the full reports go to
/// `out/harness.json`.
fn main_job() -> Result<(), String> {
    let started = std::time::Instant::now();
    let mut reports = Vec::new();
    // A progress bar on standard error (drawn on a terminal only); table
    // lines go to standard output above it.
    let bar = worley_cli::commands::progress(28, "main job");
    macro_rules! say {
        ($($t:tt)*) => { bar.suspend(|| println!($($t)*)) };
    }
    say!("worley main job: the f64 reference and the 8-lane SIMD kernel, default configuration");
    say!("(seed 0, λ {}, Euclidean); speed on one thread, checks on all cores\n", worley::config::DEFAULT_DENSITY);
    let speed = Campaign { samples: 300_000, oracle_samples: 0, pairs: 0, grid_cells: 0, ..Campaign::default() };
    let accuracy =
        Campaign { samples: 200_000, oracle_samples: 100_000, pairs: 100_000, grid_cells: 0, ..Campaign::default() };
    // Statistics over [-10^4, 10^4]^d: the 10^6 cells of the grid bias are
    // then nearly all distinct (the default range holds only about 2·10^5
    // cells in 2D, so the figure would be one small region's).
    let statistics = Campaign {
        samples: 1_000_000,
        oracle_samples: 0,
        pairs: 0,
        grid_cells: 1_000_000,
        range: 10_000.0,
        ..Campaign::default()
    };

    say!("speed (M samples/s, exact mode, random points in [-1000, 1000]^d)");
    say!("{:>4} {:>8} {:>8} {:>8}", "dim", "F1", "F2", "F4");
    for dim in 2..=4 {
        let mut row = format!("{:>4}", format!("{dim}D"));
        for order in [1, 2, 4] {
            let r = run_reference(dim, Config { order, ..Config::default() }, &speed)?;
            row += &format!(" {:>8.3}", r.throughput / 1e6);
            reports.push(r);
            bar.inc(1);
        }
        say!("{row}");
    }

    // Reference and SIMD side by side: speed next to error, per order.
    let versus =
        Campaign { samples: 300_000, oracle_samples: 50_000, pairs: 50_000, grid_cells: 0, ..Campaign::default() };
    say!(
        "\nspeed against error: reference (f64) vs SIMD (8 lanes, f32, {}), exact mode, one thread;",
        worley::simd_level()
    );
    say!(
        "error against brute force over {} samples, continuity over {} straddling pairs;",
        versus.oracle_samples,
        versus.pairs
    );
    say!("speed through the harness, which converts every result to its f64 report (see `cargo bench` for the kernels alone)");
    // Where this build chooses AVX-512 at run time, the same samples again
    // under a ceiling of AVX2: the level most CPUs run.
    let avx2_too = worley::simd::runtime_avx512();
    if avx2_too {
        say!("AVX2 M/s: the SIMD speed again under WORLEY_SIMD=avx2 (what a CPU without AVX-512 runs)");
    }
    say!(
        "{:>4} {:>5} | {:>9} {:>9} {:>6}{} | {:>10} {:>10} {:>6} {:>6}",
        "dim",
        "order",
        "ref M/s",
        "SIMD M/s",
        "ratio",
        if avx2_too { format!(" {:>9}", "AVX2 M/s") } else { String::new() },
        "ref maxerr",
        "SIMD maxerr",
        "wrong",
        "disc"
    );
    for dim in 2..=4 {
        for order in [1, 2, 4] {
            let config = Config { order, ..Config::default() };
            let r = run_reference(dim, config, &versus)?;
            let v = run_simd(dim, config, &versus)?;
            let max_err = |rep: &Report| rep.orders.iter().map(|o| o.max_error).fold(0.0, f64::max);
            let wrong: u64 = v.orders.iter().map(|o| o.oracle_disagreements + o.id_disagreements).sum();
            let disc: u64 = v.orders.iter().map(|o| o.continuity_violations).sum();
            let avx2 = if avx2_too {
                let speed_only = Campaign { oracle_samples: 0, pairs: 0, ..versus };
                let before = worley::simd::set_simd_cap(worley::simd::SimdCap::Avx2);
                let a = run_simd(dim, config, &speed_only);
                worley::simd::set_simd_cap(before);
                format!(" {:>9.3}", a?.throughput / 1e6)
            } else {
                String::new()
            };
            say!(
                "{:>4} {:>5} | {:>9.3} {:>9.3} {:>6.2}{} | {:>10.2e} {:>10.2e} {:>6} {:>6}",
                format!("{dim}D"),
                format!("F1-F{order}"),
                r.throughput / 1e6,
                v.throughput / 1e6,
                v.throughput / r.throughput,
                avx2,
                max_err(&r),
                max_err(&v),
                wrong,
                disc
            );
            reports.push(r);
            reports.push(v);
            bar.inc(1);
        }
    }

    let mut exact = Vec::new();
    let mut window = Vec::new();
    for dim in 2..=4 {
        exact.push(run_reference(dim, Config { order: 8, ..Config::default() }, &accuracy)?);
        bar.inc(1);
        window.push(run_reference(dim, Config { order: 8, mode: Mode::Window, ..Config::default() }, &accuracy)?);
        bar.inc(1);
    }
    let ppm = |n: u64| 1e6 * n as f64 / accuracy.oracle_samples as f64;
    say!(
        "\naccuracy against brute force ({} samples, {} straddling pairs per dimension)",
        accuracy.oracle_samples,
        accuracy.pairs
    );
    say!("  window: wrong F_k and discontinuous pairs (ppm) with the 3^d block only");
    say!("  exact:  wrong F_k and discontinuous pairs (counts), and % of samples needing a wider search");
    let mut head = format!("{:>5}", "order");
    for dim in 2..=4 {
        head +=
            &format!(" | {:>9} {:>9} {:>6} {:>6} {:>8}", format!("{dim}D win"), "win disc", "exact", "disc", "widen %");
    }
    say!("{head}");
    for k in 0..8 {
        let mut row = format!("{:>5}", format!("F{}", k + 1));
        for (e, w) in exact.iter().zip(&window) {
            let (eo, wo) = (&e.orders[k], &w.orders[k]);
            row += &format!(
                " | {:>9.1} {:>9.1} {:>6} {:>6} {:>8.4}",
                ppm(wo.oracle_disagreements),
                1e6 * wo.continuity_violations as f64 / accuracy.pairs as f64,
                eo.oracle_disagreements + eo.id_disagreements,
                eo.continuity_violations,
                100.0 * eo.needs_wider as f64 / accuracy.oracle_samples as f64
            );
        }
        say!("{row}");
    }
    reports.extend(exact);
    reports.extend(window);

    say!(
        "\nstatistics of F1 ({} samples, grid bias over {} cells, in [-{}, {}]^d)",
        statistics.samples,
        statistics.grid_cells,
        statistics.range,
        statistics.range
    );
    say!("{:>4} {:>9} {:>9} {:>10}", "dim", "mean F1", "KS", "grid bias");
    for dim in 2..=4 {
        let r = run_reference(dim, Config::default(), &statistics)?;
        bar.inc(1);
        say!("{:>4} {:>9.5} {:>9.5} {:>9.3}%", format!("{dim}D"), r.mean_f1, r.ks, 100.0 * r.grid_bias);
        reports.push(r);
    }

    std::fs::create_dir_all("out").map_err(|e| format!("cannot create out/: {e}"))?;
    let json = serde_json::to_string_pretty(&reports).map_err(|e| e.to_string())?;
    picture::write_output(Path::new("out/harness.json"), json.as_bytes())?;

    let drawn = std::time::Instant::now();
    bar.set_message("gallery");
    let images = worley_cli::gallery::gallery(Path::new("out/gallery"), 384, false, false)?;
    bar.inc(1);
    bar.finish_and_clear();
    say!("\ngallery ({} images, {:.1} s on all cores):", images.len(), drawn.elapsed().as_secs_f64());
    for path in &images {
        say!("  {}", path.display());
    }
    say!("full reports: out/harness.json");
    say!(
        "files are in {}/out ({:.1} s in all)",
        std::env::current_dir().map(|d| d.display().to_string()).unwrap_or_default(),
        started.elapsed().as_secs_f64()
    );
    Ok(())
}
