//! What the subcommands share (progress bars, lists, metrics) and `worley
//! ranges`.

use indicatif::{ProgressBar, ProgressStyle};

/// A progress bar on standard error (drawn only on a terminal).
pub fn progress(len: u64, what: &str) -> ProgressBar {
    let bar = ProgressBar::new(len);
    bar.set_style(
        ProgressStyle::with_template("{msg:>12} [{bar:30}] {pos}/{len} {elapsed}")
            .unwrap_or_else(|_| ProgressStyle::default_bar())
            .progress_chars("=> "),
    );
    bar.set_message(what.to_string());
    bar
}

/// The metric's command-line spelling (shared by `check` and `render`).
pub fn parse_metric(s: &str) -> Result<worley::Metric, String> {
    s.parse()
}

/// Comma-separated numbers.
pub fn parse_list<T: std::str::FromStr>(s: &str, what: &str) -> Result<Vec<T>, String> {
    s.split(',').map(|v| v.trim().parse::<T>().map_err(|_| format!("{what} {v:?} is not a number"))).collect()
}

/// Options of `worley ranges`.
#[derive(clap::Args, Debug)]
pub struct RangesArgs {
    /// Random samples per dimension and combination.
    #[arg(long, default_value_t = 1_000_000)]
    pub samples: usize,
}

/// `worley ranges`: the 0.1 % and 99.9 % quantiles of the standard
/// combinations in the default configuration, as Rust source for
/// `worley::texture::DEFAULT_RANGES`.
pub fn ranges(args: &RangesArgs) -> Result<(), String> {
    use worley::texture::{Combination, Fractal, Range, Texture, STANDARD};
    fn measure<const D: usize>(c: &Combination, samples: usize) -> Result<Range, String> {
        let t = Texture::<D, 4>::new(worley::Config::default(), c.clone(), Fractal::default(), None)
            .map_err(|e| e.to_string())?;
        Ok(t.measure_range(samples, 1))
    }
    if args.samples < 1000 {
        return Err(format!("--samples {}: use at least 1000", args.samples));
    }
    let bar = progress(3 * STANDARD.len() as u64, "ranges");
    let mut lines = Vec::new();
    for dim in 2..=4 {
        for name in STANDARD {
            let c: Combination = name.parse()?;
            let r = match dim {
                2 => measure::<2>(&c, args.samples)?,
                3 => measure::<3>(&c, args.samples)?,
                _ => measure::<4>(&c, args.samples)?,
            };
            lines.push(format!("    ({dim}, {name:?}, {:.4}, {:.4}),", r.lo, r.hi));
            bar.inc(1);
        }
    }
    bar.finish_and_clear();
    println!("// {} samples per entry: (dimension, combination, 0.1 % quantile, 99.9 % quantile)", args.samples);
    println!("pub const DEFAULT_RANGES: &[(usize, &str, f32, f32)] = &[\n{}\n];", lines.join("\n"));
    Ok(())
}
