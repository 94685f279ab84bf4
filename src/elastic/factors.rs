//! The factors of one load step: every load, force-controlled force and prescribed
//! displacement follows a load path, the default one or a named one, and is scaled at each step
//! by its path's factor (a case's `load_steps` and `[load_path]`, `docs/case-file.md`).

use std::collections::BTreeMap;

/// The factors of one load step: the default path's (the loads, forces and prescribed
/// displacements without a `path`, scaled by `load_steps`) and each named path's.
#[derive(Debug, Clone, PartialEq)]
pub struct StepFactors {
    /// The factor of everything that follows no named path.
    pub default: f64,
    /// The factor of each named path at this step (empty without a `[load_path]`).
    pub paths: BTreeMap<String, f64>,
}

impl StepFactors {
    /// A step that scales everything by `factor` (no named path): a step of `load_steps`.
    pub fn uniform(factor: f64) -> Self {
        Self {
            default: factor,
            paths: BTreeMap::new(),
        }
    }

    /// The factor of `path` (`None`: the default path); `None` for a name this step does not
    /// have (`Self::missing`).
    pub fn get(&self, path: Option<&str>) -> Option<f64> {
        match path {
            None => Some(self.default),
            Some(name) => self.paths.get(name).copied(),
        }
    }

    /// The factor of `path` (`None`: the default path).
    ///
    /// # Panics
    /// If this step has no path `path`: the solves check the paths of their problems first
    /// (`Self::missing`).
    pub fn of(&self, path: Option<&str>) -> f64 {
        self.get(path).unwrap_or_else(|| {
            panic!(
                "load path '{}' has no factor at this step (checked before the solve)",
                path.unwrap_or_default()
            )
        })
    }

    /// The first of `paths` this step has no factor for.
    pub fn missing<'a>(&self, paths: impl IntoIterator<Item = &'a str>) -> Option<&'a str> {
        paths.into_iter().find(|p| !self.paths.contains_key(*p))
    }

    /// These factors with only the named `paths` (those this step has).
    pub fn only<'a>(&self, paths: impl IntoIterator<Item = &'a str>) -> StepFactors {
        let paths = (paths.into_iter())
            .filter_map(|p| Some((p.to_string(), *self.paths.get(p)?)))
            .collect();
        StepFactors {
            default: self.default,
            paths,
        }
    }

    /// Whether every factor is finite.
    pub fn is_finite(&self) -> bool {
        self.default.is_finite() && self.paths.values().all(|f| f.is_finite())
    }

    /// The number `s` with `self = s earlier` path by path, for scaling an answer at `earlier`
    /// into a first guess at `self`: `self.default / earlier.default` without named paths
    /// (`None` if `earlier.default` is 0); with named paths, the ratio of the first path
    /// nonzero at `earlier` if every path's factor has that ratio (to 1e-12), else 1 (an answer
    /// at other proportions, taken as it is), and `None` if every factor of `earlier` is 0.
    pub fn scale_from(&self, earlier: &StepFactors) -> Option<f64> {
        if self.paths.is_empty() && earlier.paths.is_empty() {
            return (earlier.default != 0.0).then(|| self.default / earlier.default);
        }
        let pairs = || {
            std::iter::once((self.default, earlier.default)).chain(
                (self.paths.iter())
                    .map(|(name, &f)| (f, earlier.paths.get(name).copied().unwrap_or(0.0))),
            )
        };
        let (now, then) = pairs().find(|&(_, then)| then != 0.0)?;
        let ratio = now / then;
        let proportional = pairs().all(|(now, then)| {
            let scaled = ratio * then;
            (now - scaled).abs() <= 1e-12 * now.abs().max(scaled.abs())
        });
        Some(if proportional { ratio } else { 1.0 })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn step(default: f64, paths: &[(&str, f64)]) -> StepFactors {
        StepFactors {
            default,
            paths: paths.iter().map(|&(n, f)| (n.to_string(), f)).collect(),
        }
    }

    #[test]
    fn a_first_guess_scales_only_along_proportional_factors() {
        // One factor for all: the ratio of the two, none from 0.
        assert_eq!(step(1.0, &[]).scale_from(&step(0.5, &[])), Some(2.0));
        assert_eq!(step(1.0, &[]).scale_from(&step(0.0, &[])), None);
        // Every path in the same proportion: the ratio.
        let earlier = step(0.5, &[("press", 0.25)]);
        assert_eq!(step(1.0, &[("press", 0.5)]).scale_from(&earlier), Some(2.0));
        // Other proportions: the earlier answer as it is.
        assert_eq!(step(1.0, &[("press", 1.0)]).scale_from(&earlier), Some(1.0));
        // The default path at 0 throughout: the ratio of the first nonzero path.
        let earlier = step(0.0, &[("a", 0.0), ("b", 0.5)]);
        assert_eq!(
            step(0.0, &[("a", 0.0), ("b", 1.0)]).scale_from(&earlier),
            Some(2.0)
        );
        assert_eq!(
            step(1.0, &[("a", 1.0)]).scale_from(&step(0.0, &[("a", 0.0)])),
            None
        );
    }

    #[test]
    fn the_factor_of_a_path() {
        let factors = step(0.5, &[("press", 0.25)]);
        assert_eq!(factors.of(None), 0.5);
        assert_eq!(factors.of(Some("press")), 0.25);
        assert_eq!(factors.get(Some("shear")), None);
        assert_eq!(factors.missing(["press", "shear"]), Some("shear"));
        assert!(factors.is_finite());
        assert!(!step(0.5, &[("press", f64::NAN)]).is_finite());
    }
}
