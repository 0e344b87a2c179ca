//! The campaign report, as an aligned table and as JSON.

use std::fmt::Write as _;

use super::Campaign;
use worley::config::Config;
use worley::definition::Pattern;

/// Per-order results of a campaign.
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct OrderReport {
    /// Samples whose F_k differs from the oracle by more than the error bound.
    pub oracle_disagreements: u64,
    /// Samples whose k-th ID differs from the oracle's where F_k is not a tie.
    pub id_disagreements: u64,
    /// Largest |F_k − oracle| among the agreeing samples.
    pub max_error: f64,
    /// Samples whose exact F_k lies beyond the 3^d block's outside: a window
    /// search may be wrong there, an exact search widens.
    pub needs_wider: u64,
    /// Straddling pairs whose F_k jumps by more than the Lipschitz bound.
    pub continuity_violations: u64,
    /// Largest jump beyond the Lipschitz distance among the violations.
    pub max_excess: f64,
}

/// Everything a campaign measured.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Report {
    /// The kernel's name.
    pub kernel: String,
    /// Dimension.
    pub dim: usize,
    /// The kernel's configuration.
    pub config: Config,
    /// The campaign.
    pub campaign: Campaign,
    /// Cells per user unit.
    pub scale: f64,
    /// Mean population per cell of the table.
    pub table_mean: f64,
    /// Largest population of the table.
    pub table_max: u32,
    /// Samples per second on one thread.
    pub throughput: f64,
    /// Mean F1 over the random samples.
    pub mean_f1: f64,
    /// Kolmogorov–Smirnov distance of F1 from the Poisson law.
    pub ks: f64,
    /// Mean F1 at cell centres over mean F1 at cell corners, minus one (NaN
    /// when the campaign sampled no cells).
    pub grid_bias: f64,
    /// Fraction of the random samples whose search went beyond the 3^d block
    /// (NaN for a kernel that does not report its search radius).
    pub widened: f64,
    /// Largest search radius seen (in cells).
    pub max_shells: u32,
    /// Continuity pairs tried.
    pub pairs: u64,
    /// Of those, pairs whose two points lie in different cells.
    pub straddled: u64,
    /// Per order k = 1..n.
    pub orders: Vec<OrderReport>,
    /// Repeated strips of cells in a window around the origin (the cell
    /// hash against the uniform-hash expectation), when measured.
    pub repeats: Option<super::repeats::Repeats>,
    /// Grids through the coherent path against the per-sample kernel, for
    /// kernels that have both.
    pub grids: Option<super::grids::GridIdentity>,
}

impl Report {
    /// An empty report for a kernel.
    pub fn new<const D: usize>(kernel: String, config: &Config, pattern: &Pattern<D>, campaign: &Campaign) -> Self {
        Report {
            kernel,
            dim: D,
            config: *config,
            campaign: *campaign,
            scale: pattern.scale(),
            table_mean: pattern.table().mean(),
            table_max: pattern.table().max_population(),
            throughput: 0.0,
            mean_f1: 0.0,
            ks: 0.0,
            grid_bias: 0.0,
            widened: 0.0,
            max_shells: 0,
            pairs: 0,
            straddled: 0,
            orders: vec![OrderReport::default(); config.order],
            repeats: None,
            grids: None,
        }
    }

    /// True when the kernel agreed with the oracle everywhere and no pair
    /// violated continuity.
    pub fn is_exact(&self) -> bool {
        self.orders
            .iter()
            .all(|o| o.oracle_disagreements == 0 && o.id_disagreements == 0 && o.continuity_violations == 0)
            && self.grids.is_none_or(|g| g.differing == 0 && g.texture_differing == 0)
    }

    /// The report as pretty-printed JSON.
    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).unwrap_or_else(|e| format!("{{\"error\": \"{e}\"}}"))
    }

    /// The report as an aligned text table.
    pub fn to_table(&self) -> String {
        let c = &self.config;
        let mut s = String::new();
        let _ = writeln!(
            s,
            "{} {}D order {} {} {} seed {} λ {} (table mean {:.4}, max {}) bump {}",
            self.kernel,
            self.dim,
            c.order,
            c.metric,
            c.mode,
            c.seed,
            c.density,
            self.table_mean,
            self.table_max,
            c.bump
        );
        let _ = writeln!(
            s,
            "  {:.3} M samples/s (1 thread)   mean F1 {:.5}   KS {:.5}   grid bias {}   widened {}   max shells {}",
            self.throughput / 1e6,
            self.mean_f1,
            self.ks,
            if self.grid_bias.is_nan() { "n/a".to_string() } else { format!("{:+.3}%", 100.0 * self.grid_bias) },
            if self.widened.is_nan() { "n/a".to_string() } else { format!("{:.4}%", 100.0 * self.widened) },
            self.max_shells
        );
        let _ = writeln!(
            s,
            "  {} samples, {} against the oracle, {} pairs ({} straddling)",
            self.campaign.samples, self.campaign.oracle_samples, self.pairs, self.straddled
        );
        let _ = writeln!(
            s,
            "  {:>5} {:>16} {:>10} {:>12} {:>18} {:>12} {:>12}",
            "order", "wrong F_k", "wrong ID", "max error", "beyond block", "discontin.", "max excess"
        );
        let per = |n: u64, of: usize| format!("{n} ({:.1} ppm)", 1e6 * n as f64 / of.max(1) as f64);
        for (k, o) in self.orders.iter().enumerate() {
            let _ = writeln!(
                s,
                "  {:>5} {:>16} {:>10} {:>12.3e} {:>18} {:>12} {:>12.3e}",
                format!("F{}", k + 1),
                per(o.oracle_disagreements, self.campaign.oracle_samples),
                o.id_disagreements,
                o.max_error,
                per(o.needs_wider, self.campaign.oracle_samples),
                o.continuity_violations,
                o.max_excess
            );
        }
        if let Some(r) = &self.repeats {
            let _ = writeln!(
                s,
                "  cell hash, {} cells around the origin: {} repeated runs of two cells (a uniform hash: {:.1e}), {} equal cells (a uniform hash: {:.0})",
                r.cells, r.equal_runs, r.expected_equal_runs, r.equal_cells, r.expected_equal_cells
            );
        }
        if let Some(g) = &self.grids {
            let _ = writeln!(
                s,
                "  grids: {} grids ({} on the coherent path), {} samples, {} differing in any bit from the per-sample kernel; \
                 a 3-octave texture's grid values: {} samples, {} differing from its per-point value",
                g.grids, g.coherent, g.samples, g.differing, g.texture_samples, g.texture_differing
            );
        }
        s
    }
}
