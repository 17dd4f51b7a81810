//! `[sweep]`: the expansion of a case into one concrete case per swept value.

use super::parse::KeyPath;
use super::*;

/// A friction parameter that can be swept.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum FrictionParam {
    Mu,
    Kt,
    Kn,
    N0,
}

pub(super) const FRICTION_PARAMS: [(&str, FrictionParam); 4] = [
    ("mu", FrictionParam::Mu),
    ("kt", FrictionParam::Kt),
    ("kn", FrictionParam::Kn),
    ("n0", FrictionParam::N0),
];

/// The sweepable parameters of a `[[strip]]` (its total preload is `preload`).
pub(super) const STRIP_PARAMS: [(&str, FrictionParam); 4] = [
    ("mu", FrictionParam::Mu),
    ("kt", FrictionParam::Kt),
    ("kn", FrictionParam::Kn),
    ("preload", FrictionParam::N0),
];

/// What a sweep path sets.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum SweepTarget {
    Contact(usize, FrictionParam),
    Element(usize, FrictionParam),
    Strip(usize, FrictionParam),
    DampingModal,
    ForceScale,
}

impl Case {
    /// One case per sweep point, with the swept parameters applied (a case without a sweep gives
    /// one point: itself). Several sweep keys are zipped: their lists must have equal lengths.
    ///
    /// Sweepable parameter paths:
    /// - `contact.<name>.mu|kt|kn|n0` — a `[[contact]]` by name;
    /// - `element.<index>.mu|kt|kn|n0` — an `[[element]]` by 0-based index (the parameters of
    ///   its kind: all four for `friction`, `mu` and `n0` for `tanh_friction`);
    /// - `strip.<name>.mu|kt|kn|preload` — a `[[strip]]` by its name (`strip<s>` when unnamed);
    /// - `model.damping.modal` — the modal damping ratio (the case must use modal damping);
    /// - `excitation.force_scale` — a factor on the excitation forces.
    ///
    /// Each point has an empty `sweep` table and its [`SweepPoint`] set; its values are validated
    /// like the case file's.
    pub fn sweep_points(&self) -> Result<Vec<Case>> {
        let n = self.sweep_length()?;
        let targets: Vec<(&String, &Vec<f64>, SweepTarget)> = self
            .sweep
            .iter()
            .map(|(k, v)| self.sweep_target(k).map(|t| (k, v, t)))
            .collect::<Result<_>>()?;
        (0..n)
            .map(|i| {
                let mut point = self.clone();
                point.sweep.clear();
                let mut values = Vec::with_capacity(targets.len());
                for (key, list, target) in &targets {
                    point.apply_sweep(*target, list[i]);
                    values.push(((*key).clone(), list[i]));
                }
                point.sweep_point = Some(SweepPoint { index: i, values });
                point.validate_sweep_point(&targets, i)?;
                Ok(point)
            })
            .collect()
    }

    /// The number of sweep points (1 without a sweep); errors on empty or unequal lists.
    pub(super) fn sweep_length(&self) -> Result<usize> {
        let mut lens = self.sweep.iter().map(|(k, v)| (k, v.len()));
        let Some((first_key, n)) = lens.next() else {
            return Ok(1);
        };
        if n == 0 {
            return Err(self.key_error(
                &KeyPath::sweep(first_key, None),
                "the list of values is empty",
            ));
        }
        match lens.find(|(_, m)| *m != n) {
            None => Ok(n),
            Some((k, m)) => Err(self.key_error(
                &KeyPath::sweep(k, None),
                format!("has {m} values but '{first_key}' has {n}; several sweep keys are zipped point by point, so their lists need equal lengths"),
            )),
        }
    }

    /// Parses a sweep path against this case's contacts and elements.
    pub(super) fn sweep_target(&self, path: &str) -> Result<SweepTarget> {
        let parts: Vec<&str> = path.split('.').collect();
        let param = |p: &str| {
            FRICTION_PARAMS
                .iter()
                .find(|(n, _)| *n == p)
                .map(|(_, f)| *f)
        };
        let target = match parts.as_slice() {
            ["contact", name, p] => self
                .contact
                .iter()
                .position(|c| c.name == *name)
                .zip(param(p))
                .map(|(i, f)| SweepTarget::Contact(i, f)),
            ["element", idx, p] => idx
                .parse::<usize>()
                .ok()
                .filter(|i| *i < self.element.len() && self.element[*i].sweepable(p))
                .zip(param(p))
                .map(|(i, f)| SweepTarget::Element(i, f)),
            ["strip", name, p] => (0..self.strip.len())
                .find(|&s| self.strip[s].label(s) == *name)
                .zip(STRIP_PARAMS.iter().find(|(n, _)| n == p).map(|(_, f)| *f))
                .map(|(s, f)| SweepTarget::Strip(s, f)),
            ["model", "damping", "modal"]
                if matches!(self.model.damping, Some(Damping::Modal(_))) =>
            {
                Some(SweepTarget::DampingModal)
            }
            ["excitation", "force_scale"] if self.excitation.is_some() => {
                Some(SweepTarget::ForceScale)
            }
            _ => None,
        };
        target.ok_or_else(|| {
            self.key_error(
                &KeyPath::sweep(path, None),
                format!(
                    "unknown sweep parameter '{path}'; this case can sweep: {}",
                    self.sweep_paths().join(", ")
                ),
            )
        })
    }

    /// The sweep paths valid for this case.
    pub fn sweep_paths(&self) -> Vec<String> {
        let mut out = Vec::new();
        for c in &self.contact {
            out.extend(
                FRICTION_PARAMS
                    .iter()
                    .map(|(p, _)| format!("contact.{}.{p}", c.name)),
            );
        }
        for (i, e) in self.element.iter().enumerate() {
            out.extend(
                FRICTION_PARAMS
                    .iter()
                    .filter(|(p, _)| e.sweepable(p))
                    .map(|(p, _)| format!("element.{i}.{p}")),
            );
        }
        for (s, strip) in self.strip.iter().enumerate() {
            let label = strip.label(s);
            out.extend(
                STRIP_PARAMS
                    .iter()
                    .map(|(p, _)| format!("strip.{label}.{p}")),
            );
        }
        if matches!(self.model.damping, Some(Damping::Modal(_))) {
            out.push("model.damping.modal".into());
        }
        if self.excitation.is_some() {
            out.push("excitation.force_scale".into());
        }
        if out.is_empty() {
            out.push(
                "none (the case has no contact, element, strip, modal damping or excitation)"
                    .into(),
            );
        }
        out
    }

    /// Sets the swept parameter to `v`.
    pub(super) fn apply_sweep(&mut self, target: SweepTarget, v: f64) {
        let set = |f: FrictionParam, mu: &mut f64, kt: &mut f64, kn: &mut f64, n0: &mut f64| match f
        {
            FrictionParam::Mu => *mu = v,
            FrictionParam::Kt => *kt = v,
            FrictionParam::Kn => *kn = v,
            FrictionParam::N0 => *n0 = v,
        };
        match target {
            SweepTarget::Contact(i, f) => {
                let c = &mut self.contact[i];
                set(f, &mut c.mu, &mut c.kt, &mut c.kn, &mut c.n0);
            }
            SweepTarget::Element(i, f) => {
                let e = &mut self.element[i];
                match f {
                    FrictionParam::Mu => e.mu = Some(v),
                    FrictionParam::Kt => e.kt = Some(v),
                    FrictionParam::Kn => e.kn = v,
                    FrictionParam::N0 => e.n0 = Some(v),
                }
            }
            SweepTarget::Strip(s, f) => {
                let st = &mut self.strip[s];
                set(f, &mut st.mu, &mut st.kt, &mut st.kn, &mut st.preload);
            }
            SweepTarget::DampingModal => self.model.damping = Some(Damping::Modal(v)),
            SweepTarget::ForceScale => {
                if let Some(e) = &mut self.excitation {
                    e.force_scale = v;
                }
            }
        }
    }

    /// Validates a sweep point; an error names the sweep value that caused it.
    pub(super) fn validate_sweep_point(
        &self,
        targets: &[(&String, &Vec<f64>, SweepTarget)],
        i: usize,
    ) -> Result<()> {
        if targets.is_empty() {
            return Ok(());
        }
        self.validate().map_err(|e| {
            let key = targets[0].0;
            let values: Vec<String> = targets
                .iter()
                .map(|(k, l, _)| format!("{k} = {}", l[i]))
                .collect();
            let what = format!("sweep point {i} ({}) is invalid: {e}", values.join(", "));
            self.key_error(&KeyPath::sweep(key, Some(i)), what)
        })
    }
}
