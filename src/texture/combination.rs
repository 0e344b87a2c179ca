//! How F1..Fn are combined into one value ([`Combination`]): the
//! chapter's combinations, any weighted sum, the border distance, compact
//! smooth F1, the n-sphere radius, and their names on the command line.

use wide::f32x8;

use super::TextureError;

/// How F1..Fn are combined into one value.
#[derive(Clone, Debug, PartialEq)]
pub enum Combination {
    /// Σ c_k F_k with `c[k − 1]` the coefficient of F_k (at most n of them).
    Linear(Vec<f32>),
    /// F1 · F2.
    Product,
    /// F3² − F2².
    SquareDifference,
    /// The distance to the border of the sample's Voronoi cell
    /// ([`SimdBorder`](crate::SimdBorder)): even lines whatever the spacing of the points,
    /// where F2 − F1 widens between close pairs. Euclidean only; its
    /// gradient is the border plane's normal.
    Border,
    /// Compact smooth F1 with smoothness `s` ([`SimdSmooth`](crate::SimdSmooth)):
    /// rounded cells, C∞, with an analytic gradient. `s` is a length in
    /// the units of the octave's F1 (user units, periodic textures too),
    /// so each octave is rounded alike. Euclidean only.
    Smooth(f32),
    /// The n-sphere radius ([`SimdNSphere`](crate::SimdNSphere)): half the
    /// distance from F1's point to its nearest other point, constant over
    /// each Voronoi cell (its gradient is 0): a disc or ball of this radius
    /// around each point fits inside its cell. Euclidean only.
    NSphere,
}

impl Combination {
    /// F_k alone.
    pub fn f(k: usize) -> Self {
        let mut c = vec![0.0; k.max(1)];
        c[k.max(1) - 1] = 1.0;
        Combination::Linear(c)
    }

    /// F2 − F1, the "crackle" of cell borders.
    pub fn crackle() -> Self {
        Combination::Linear(vec![-1.0, 1.0])
    }

    /// The smallest order that computes this combination.
    pub fn order(&self) -> usize {
        match self {
            Combination::Linear(c) => c.len(),
            Combination::Product => 2,
            Combination::SquareDifference => 3,
            Combination::Border | Combination::Smooth(_) | Combination::NSphere => 1,
        }
    }

    /// A short name, e.g. `F2-F1`, `0.5F1+2F3`, `F1*F2`, `border`,
    /// `smooth:0.3`, `n-sphere`.
    pub fn name(&self) -> String {
        match self {
            Combination::Product => "F1*F2".into(),
            Combination::Border => "border".into(),
            Combination::Smooth(v) => format!("smooth:{v}"),
            Combination::NSphere => "n-sphere".into(),
            Combination::SquareDifference => "F3^2-F2^2".into(),
            Combination::Linear(c) => {
                let mut s = String::new();
                for (k, &v) in c.iter().enumerate().filter(|(_, v)| **v != 0.0) {
                    let sign = if v < 0.0 {
                        "-"
                    } else if s.is_empty() {
                        ""
                    } else {
                        "+"
                    };
                    let m = v.abs();
                    let coefficient = if m == 1.0 { String::new() } else { format!("{m}") };
                    s += &format!("{sign}{coefficient}F{}", k + 1);
                }
                if s.is_empty() {
                    "0".into()
                } else {
                    s
                }
            }
        }
    }

    pub(super) fn validate(&self, compiled: usize) -> Result<(), TextureError> {
        if let Combination::Smooth(v) = *self
            && !(v >= 0.0 && v.is_finite())
        {
            return Err(TextureError::Smoothness(v));
        }
        if let Combination::Linear(c) = self {
            if c.is_empty() {
                return Err(TextureError::NoCoefficients);
            }
            if let Some(k) = c.iter().position(|v| !v.is_finite()) {
                return Err(TextureError::Coefficient { index: k + 1, value: c[k] });
            }
        }
        if self.order() > compiled {
            return Err(TextureError::Order { needs: self.order(), compiled });
        }
        Ok(())
    }

    /// The combination of distances, in lanes. [`Combination::Border`],
    /// [`Combination::Smooth`] and [`Combination::NSphere`] are not
    /// functions of the sample's distances: textures evaluate them through
    /// their own kernels and never call this for them (NaN if they did).
    #[inline(always)]
    pub(super) fn value<const N: usize>(&self, f: &[f32x8; N]) -> f32x8 {
        match self {
            Combination::Border | Combination::Smooth(_) | Combination::NSphere => f32x8::splat(f32::NAN),
            Combination::Linear(c) => {
                let mut v = f32x8::splat(0.0);
                for (ck, fk) in c.iter().zip(f) {
                    v += f32x8::splat(*ck) * *fk;
                }
                v
            }
            Combination::Product => f[0] * f[1],
            Combination::SquareDifference => f[2] * f[2] - f[1] * f[1],
        }
    }

    /// d(combination)/d(F_k) for each k, in lanes (none for the
    /// combinations with a kernel of their own, whose gradients come from
    /// their kernels).
    pub(super) fn weights<const N: usize>(&self, f: &[f32x8; N]) -> [f32x8; N] {
        let mut w = [f32x8::splat(0.0); N];
        match self {
            Combination::Border | Combination::Smooth(_) | Combination::NSphere => {}
            Combination::Linear(c) => {
                for (wk, ck) in w.iter_mut().zip(c) {
                    *wk = f32x8::splat(*ck);
                }
            }
            Combination::Product => {
                w[0] = f[1];
                w[1] = f[0];
            }
            Combination::SquareDifference => {
                w[1] = f32x8::splat(-2.0) * f[1];
                w[2] = f32x8::splat(2.0) * f[2];
            }
        }
        w
    }
}

impl std::str::FromStr for Combination {
    type Err = String;

    /// `F1*F2`, `F3^2-F2^2`, `border`, `smooth:<s>` (compact smooth F1,
    /// e.g. `smooth:0.3`), `n-sphere`, or a linear sum of terms `[c]F<k>` such as
    /// `F2-F1`, `0.5F1+2F3`, `-1.5*F2+F4` (k from 1 to 16).
    fn from_str(s: &str) -> Result<Self, String> {
        let t: String = s.chars().filter(|c| !c.is_whitespace()).collect();
        let usage =
            "use F1*F2, F3^2-F2^2, border, smooth:<s>, n-sphere, or a sum of terms [c]Fk such as F2-F1 or 0.5F1+2F3";
        if let Some(v) = t.strip_prefix("smooth:") {
            return match v.parse::<f32>() {
                Ok(v) if v >= 0.0 && v.is_finite() => Ok(Combination::Smooth(v)),
                _ => Err(format!("{s:?}: the smoothness {v:?} is not a finite number >= 0: {usage}")),
            };
        }
        match t.as_str() {
            "F1*F2" => return Ok(Combination::Product),
            "border" => return Ok(Combination::Border),
            "n-sphere" => return Ok(Combination::NSphere),
            "F3^2-F2^2" => return Ok(Combination::SquareDifference),
            "" => return Err(format!("empty combination: {usage}")),
            _ => {}
        }
        let mut coefficients = Vec::new();
        let mut rest = t.as_str();
        while !rest.is_empty() {
            let sign = match rest.as_bytes()[0] {
                b'-' => -1.0,
                _ => 1.0,
            };
            if rest.starts_with(['+', '-']) {
                rest = &rest[1..];
            }
            let f = rest.find('F').ok_or_else(|| format!("{s:?}: a term without F: {usage}"))?;
            let number = rest[..f].trim_end_matches('*');
            let c: f32 = if number.is_empty() {
                1.0
            } else {
                number.parse().map_err(|_| format!("{s:?}: coefficient {number:?} is not a number: {usage}"))?
            };
            let digits = rest[f + 1..].find(['+', '-']).map_or(rest.len(), |e| f + 1 + e);
            let k: usize = rest[f + 1..digits]
                .parse()
                .map_err(|_| format!("{s:?}: F{} is not F1..F16: {usage}", &rest[f + 1..digits]))?;
            if !(1..=crate::config::MAX_ORDER).contains(&k) {
                return Err(format!("{s:?}: F{k} is not F1..F16: {usage}"));
            }
            if coefficients.len() < k {
                coefficients.resize(k, 0.0);
            }
            coefficients[k - 1] += sign * c;
            rest = &rest[digits..];
        }
        Ok(Combination::Linear(coefficients))
    }
}

/// The standard combinations whose output ranges are tabulated.
pub const STANDARD: [&str; 7] = ["F1", "F2", "F3", "F4", "F2-F1", "F1*F2", "F3^2-F2^2"];
