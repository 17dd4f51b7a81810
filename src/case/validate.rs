//! The validation of a parsed case: ranges, units, required and exclusive keys, each error
//! naming its key.

use super::parse::KeyPath;
use super::*;

impl Case {
    /// Checks ranges and the consistency of the tables (everything that needs no mesh or matrix).
    pub fn validate(&self) -> Result<()> {
        self.validate_model()?;
        self.validate_damping()?;
        self.validate_cyclic()?;
        self.validate_reduction()?;
        self.validate_contacts()?;
        self.validate_excitation()?;
        self.validate_response()?;
        self.validate_elements()?;
        self.validate_strips()?;
        self.validate_obstacles()?;
        self.validate_casings()?;
        self.validate_harmonic_balance()?;
        self.validate_continuation()?;
        self.validate_march()?;
        self.validate_damper()
    }

    pub(super) fn validate_model(&self) -> Result<()> {
        let m = &self.model;
        if self.damper.is_some() {
            let empty = m.mesh.is_none() && m.stiffness.is_none() && m.mass.is_none();
            return self.require(empty, "model", || {
                "a case with [damper] defines its model there; remove `mesh`/`stiffness`/`mass` from [model]"
            });
        }
        match (&m.stiffness, &m.mass) {
            (Some(_), None) => {
                return Err(self.key_error(
                    &KeyPath::parse("model.stiffness"),
                    "`stiffness` needs `mass` too (both Matrix Market files)",
                ))
            }
            (None, Some(_)) => {
                return Err(self.key_error(
                    &KeyPath::parse("model.mass"),
                    "`mass` needs `stiffness` too (both Matrix Market files)",
                ))
            }
            _ => {}
        }
        let matrices = m.stiffness.is_some();
        if m.mesh.is_none() && !matrices {
            return Err(self.key_error(
                &KeyPath::parse("model"),
                "give `mesh = \"FILE.msh\"` or both `stiffness` and `mass` (Matrix Market files)",
            ));
        }
        if m.mesh.is_some() && !matrices && m.material.is_none() && m.materials.is_empty() {
            return Err(self.key_error(&KeyPath::parse("model"), "a model assembled from the mesh needs `material = { young = ..., poisson = ..., density = ... }`"));
        }
        if let Some(mat) = &m.material {
            self.check_material("model.material", mat)?;
        }
        for (i, gm) in m.materials.iter().enumerate() {
            self.check_material(&format!("model.materials[{i}]"), &gm.material())?;
        }
        for (key, degree) in [
            ("stiffness", m.quadrature.stiffness),
            ("mass", m.quadrature.mass),
        ] {
            if let Some(d) = degree {
                self.require(
                    (1..=20).contains(&d),
                    &format!("model.quadrature.{key}"),
                    || format!("the rule's polynomial degree must be 1..=20 (found {d})"),
                )?;
            }
        }
        if m.mesh.is_none() {
            self.check_matrix_model()?;
        }
        Ok(())
    }

    pub(super) fn check_material(&self, key: &str, m: &Material) -> Result<()> {
        self.positive(&format!("{key}.young"), m.young)?;
        self.positive(&format!("{key}.density"), m.density)?;
        let nu = m.poisson;
        self.require(
            nu.is_finite() && nu > -1.0 && nu < 0.5,
            &format!("{key}.poisson"),
            || format!("Poisson's ratio must satisfy -1 < ν < 0.5 (found {nu})"),
        )
    }

    /// A model without a mesh has no groups: nothing may name one.
    pub(super) fn check_matrix_model(&self) -> Result<()> {
        let no_mesh = "needs `model.mesh`; a model given by matrices alone has no groups";
        let mut uses: Vec<&str> = Vec::new();
        if !self.model.clamp.is_empty() {
            uses.push("model.clamp");
        }
        if !self.model.materials.is_empty() {
            uses.push("model.materials");
        }
        if self.cyclic.is_some() {
            uses.push("cyclic");
        }
        if !self.contact.is_empty() {
            uses.push("contact");
        }
        if matches!(
            self.excitation,
            Some(Excitation {
                load: ExcitationLoad::Group { .. },
                ..
            })
        ) {
            uses.push("excitation.group");
        }
        if self.response.as_ref().is_some_and(|r| !r.groups.is_empty()) {
            uses.push("response.groups");
        }
        if self.reduction.as_ref().is_some_and(|r| !r.keep.is_empty()) {
            uses.push("reduction.keep");
        }
        match uses.first() {
            None => Ok(()),
            Some(k) => Err(self.key_error(&KeyPath::parse(k), no_mesh)),
        }
    }

    pub(super) fn validate_damping(&self) -> Result<()> {
        match &self.model.damping {
            Some(Damping::Modal(z)) => {
                let ok = z.is_finite() && (0.0..1.0).contains(z);
                self.require(ok, "model.damping.modal", || {
                    format!("the modal damping ratio must satisfy 0 ≤ ζ < 1 (found {z})")
                })
            }
            Some(Damping::Rayleigh { alpha, beta }) => {
                self.non_negative("model.damping.rayleigh[0]", *alpha)?;
                self.non_negative("model.damping.rayleigh[1]", *beta)
            }
            _ => Ok(()),
        }
    }

    pub(super) fn validate_cyclic(&self) -> Result<()> {
        let Some(c) = &self.cyclic else { return Ok(()) };
        self.require(c.sectors >= 2, "cyclic.sectors", || {
            format!("needs at least 2 sectors (found {})", c.sectors)
        })?;
        self.finite("cyclic.axis.origin", &c.axis.origin)?;
        self.finite("cyclic.axis.direction", &c.axis.direction)?;
        self.require(
            norm(c.axis.direction) > 0.0,
            "cyclic.axis.direction",
            || "the axis direction must not be zero",
        )?;
        self.require(c.low != c.high, "cyclic.high", || {
            format!("the low and high frontiers are the same group '{}'", c.low)
        })?;
        let needs_eo = self
            .excitation
            .as_ref()
            .is_some_and(|e| e.engine_order.is_none());
        self.require(!needs_eo, "excitation", || {
            "a cyclic model needs `engine_order` (the excitation's engine order m)"
        })
    }

    pub(super) fn validate_reduction(&self) -> Result<()> {
        let Some(r) = &self.reduction else {
            return Ok(());
        };
        self.require(r.gsi_modes != Some(0), "reduction.gsi_modes", || {
            "must be ≥ 1; omit it to keep all frontier DOF"
        })
    }

    pub(super) fn validate_contacts(&self) -> Result<()> {
        let mut names = HashSet::new();
        for (i, c) in self.contact.iter().enumerate() {
            let key = format!("contact[{i}]");
            let ok_name = !c.name.trim().is_empty() && !c.name.contains('.');
            self.require(ok_name, &format!("{key}.name"), || format!("'{}' is not a usable name: it must be non-empty and contain no '.' (sweep paths are contact.<name>.<field>)", c.name))?;
            self.require(
                names.insert(c.name.as_str()),
                &format!("{key}.name"),
                || {
                    format!(
                        "contact name '{}' is used twice; names must be unique",
                        c.name
                    )
                },
            )?;
            self.check_friction(&key, c.mu, c.kt, c.kn, c.n0, true)?;
            self.require(
                c.evaluation != Evaluation::Analytic || c.element == ContactElement::OneD,
                &format!("{key}.evaluation"),
                || "evaluation = \"analytic\" is the exact cycle of the 1-D friction law; the 2-D (Coulomb disc) element is evaluated by the AFT only (element = \"1d\" or evaluation = \"aft\")",
            )?;
            self.require(
                c.coupling.is_none() || c.model == ContactModel::Sama,
                &format!("{key}.coupling"),
                || {
                    "`coupling` applies to `model = \"sama\"` only (node-to-node pairs have one \
                     target node each); remove it or set `model = \"sama\"`"
                },
            )?;
            if let Some(m) = &c.misalignment {
                self.check_misalignment(&format!("{key}.misalignment"), m)?;
            }
        }
        Ok(())
    }

    /// Ranges of friction parameters; `normal`: whether the element has a normal direction.
    pub(super) fn check_friction(
        &self,
        key: &str,
        mu: f64,
        kt: f64,
        kn: f64,
        n0: f64,
        normal: bool,
    ) -> Result<()> {
        self.non_negative(&format!("{key}.mu"), mu)?;
        self.non_negative(&format!("{key}.kt"), kt)?;
        self.non_negative(&format!("{key}.kn"), kn)?;
        self.finite(&format!("{key}.n0"), &[n0])?;
        let n0_key = format!("{key}.n0");
        if !normal {
            return self.require(n0 >= 0.0, &n0_key, || {
                format!("without a `normal` direction the slip limit is mu·n0, so n0 must be ≥ 0 (found {n0})")
            });
        }
        self.require(n0 >= 0.0 || kn > 0.0, &n0_key, || {
            format!("n0 = {n0} < 0 means an initial gap -n0/kn, which needs kn > 0")
        })
    }

    pub(super) fn check_misalignment(&self, key: &str, m: &Misalignment) -> Result<()> {
        self.finite(&format!("{key}.translate"), &m.translate)?;
        let Some(r) = &m.rotate else { return Ok(()) };
        self.finite(&format!("{key}.rotate.axis"), &r.axis)?;
        self.finite(&format!("{key}.rotate.origin"), &r.origin)?;
        self.finite(&format!("{key}.rotate.angle_deg"), &[r.angle_deg])?;
        self.require(norm(r.axis) > 0.0, &format!("{key}.rotate.axis"), || {
            "the rotation axis must not be zero"
        })
    }

    pub(super) fn validate_excitation(&self) -> Result<()> {
        let Some(e) = &self.excitation else {
            return Ok(());
        };
        self.finite("excitation.force_scale", &[e.force_scale])?;
        match &e.load {
            ExcitationLoad::Group { force, .. } => self.finite("excitation.force", force),
            ExcitationLoad::Dofs { force, .. } => self.finite("excitation.force", force),
        }
    }

    pub(super) fn validate_response(&self) -> Result<()> {
        let Some(r) = &self.response else {
            return Ok(());
        };
        self.require(r.groups.is_empty() || r.dofs.is_empty(), "response", || {
            "give either `groups` (mesh models) or `dofs` (matrix rows), not both"
        })
    }

    pub(super) fn validate_elements(&self) -> Result<()> {
        for (i, e) in self.element.iter().enumerate() {
            let key = format!("element[{i}]");
            self.check_weighted(&format!("{key}.tangential"), &e.tangential)?;
            self.check_element_keys(&key, e)?;
            if let Some(n) = &e.normal {
                self.check_weighted(&format!("{key}.normal"), n)?;
            }
            self.check_element_values(&key, e)?;
        }
        Ok(())
    }

    /// A strip on matrix rows: rows, stations and weight tables of matching shapes, no face keys.
    fn validate_line_strip(&self, i: usize, s: &Strip) -> Result<()> {
        let k = |name: &str| format!("strip[{i}].{name}");
        let n = s.stations.len();
        self.require(s.direction.is_none(), &k("direction"), || {
            "`direction` is the slip direction of a strip on a `face`; a strip on matrix rows takes its direction from the `tangential` weights"
        })?;
        self.require(!s.dofs.is_empty(), &k("dofs"), || {
            "needs at least one matrix row (or give `face` and `direction` for a strip on a mesh face group)"
        })?;
        self.finite(&k("stations"), &s.stations)?;
        self.require(
            n >= 2 && s.stations.windows(2).all(|w| w[1] > w[0]),
            &k("stations"),
            || format!("needs at least two strictly increasing positions (found {n})"),
        )?;
        for (name, table) in [
            ("tangential", Some(&s.tangential)),
            ("normal", s.normal.as_ref()),
        ] {
            let Some(t) = table else { continue };
            self.require(t.len() == n, &k(name), || {
                format!("needs one row per station ({n}), found {}", t.len())
            })?;
            for (j, row) in t.iter().enumerate() {
                self.require(row.len() == s.dofs.len(), &k(name), || {
                    format!(
                        "row {j} has {} weights; it needs one per entry of `dofs` ({})",
                        row.len(),
                        s.dofs.len()
                    )
                })?;
                self.finite(&k(name), row)?;
            }
        }
        Ok(())
    }

    /// A strip on a mesh face: a mesh model, a non-zero finite `direction`, none of the keys of a
    /// strip on matrix rows.
    fn validate_face_strip(&self, i: usize, s: &Strip) -> Result<()> {
        let k = |name: &str| format!("strip[{i}].{name}");
        self.require(self.model.mesh.is_some(), &k("face"), || {
            "a strip on a face group needs a mesh model (`[model] mesh`)"
        })?;
        for (name, given) in [
            ("dofs", !s.dofs.is_empty()),
            ("stations", !s.stations.is_empty()),
            ("tangential", !s.tangential.is_empty()),
            ("normal", s.normal.is_some()),
        ] {
            self.require(!given, &k(name), || {
                format!("`{name}` belongs to a strip on matrix rows; a strip on a `face` reads the face's nodes (remove `{name}`, or remove `face` and `direction`)")
            })?;
        }
        let Some(d) = s.direction else {
            return Err(self.key_error(
                &KeyPath::parse(&k("face")),
                "a strip on a face needs `direction = [px, py, pz]`, the slip direction in the face's plane",
            ));
        };
        self.finite(&k("direction"), &d)?;
        self.require(norm(d) > 0.0, &k("direction"), || {
            "must not be the zero vector"
        })?;
        Ok(())
    }

    /// `[[strip]]`: station table shapes, ranges, and a preload distribution that keeps one sign.
    pub(super) fn validate_strips(&self) -> Result<()> {
        for (i, s) in self.strip.iter().enumerate() {
            let key = format!("strip[{i}]");
            let k = |name: &str| format!("{key}.{name}");
            let n = s.stations.len();
            if s.face.is_some() {
                self.validate_face_strip(i, s)?;
            } else {
                self.validate_line_strip(i, s)?;
            }
            self.require(
                (1..=strip::MAX_GAUSS).contains(&s.gauss),
                &k("gauss"),
                || {
                    format!(
                        "Gauss points per segment must be 1 to {} (found {})",
                        strip::MAX_GAUSS,
                        s.gauss
                    )
                },
            )?;
            self.non_negative(&k("kt"), s.kt)?;
            self.non_negative(&k("kn"), s.kn)?;
            self.non_negative(&k("mu"), s.mu)?;
            self.finite(&k("preload"), &[s.preload])?;
            self.require(
                s.preload >= 0.0 || ((s.normal.is_some() || s.face.is_some()) && s.kn > 0.0),
                &k("preload"),
                || {
                    format!(
                        "a negative total preload ({}) is an initial gap; it needs the normal motion (`normal` weights, or `face`) and kn > 0",
                        s.preload
                    )
                },
            )?;
            let dist = s.distribution;
            let needs_c = dist == PreloadDistribution::Quadratic;
            let needs_values = dist == PreloadDistribution::Stations;
            self.require(s.c.is_some() == needs_c, &k("c"), || {
                format!(
                    "`c` is the coefficient of distribution = \"quadratic\" (here distribution = \"{}\"): give it exactly then",
                    dist.name()
                )
            })?;
            self.require(s.values.is_some() == needs_values, &k("values"), || {
                format!(
                    "`values` are the station preloads of distribution = \"stations\" (here distribution = \"{}\"): give them exactly then",
                    dist.name()
                )
            })?;
            if let Some(c) = s.c {
                self.finite(&k("c"), &[c])?;
                self.require(c >= -1.0, &k("c"), || {
                    format!(
                        "q(s) ∝ 1 + c(2ξ − 1)² is negative at the strip's ends for c < −1 (found {c}): the distribution would give points a negative preload (and a negative stiffness where they close)"
                    )
                })?;
            }
            if let Some(v) = &s.values {
                self.require(s.face.is_none(), &k("distribution"), || {
                    "distribution = \"stations\" gives values at `stations`, which a strip on a `face` has none of; use \"uniform\" or \"quadratic\""
                })?;
                self.require(v.len() == n, &k("values"), || {
                    format!("needs one value per station ({n}), found {}", v.len())
                })?;
                self.finite(&k("values"), v)?;
                self.require(
                    v.iter().all(|&x| x >= 0.0) && v.iter().any(|&x| x > 0.0),
                    &k("values"),
                    || "relative preloads must be ≥ 0 and not all 0 (a sign change would give points a negative preload); the sign of the total is `preload`'s",
                )?;
            }
            if let Some(name) = &s.name {
                self.require(!name.is_empty() && !name.contains('/'), &k("name"), || {
                    format!("{name:?} is not a results-file group name (empty, or contains '/')")
                })?;
            }
            let label = s.label(i);
            self.require(
                self.strip[..i]
                    .iter()
                    .enumerate()
                    .all(|(j, o)| o.label(j) != label),
                &k("name"),
                || format!("another strip is named {label:?}; names must be unique"),
            )?;
            if let Some(m) = s.map {
                self.require((4..=strip::MAX_MAP_PHASES).contains(&m), &k("map"), || {
                    format!(
                        "the number of phase angles must be 4 to {} (found {m})",
                        strip::MAX_MAP_PHASES
                    )
                })?;
                self.require(self.harmonic_balance.harmonics == 1, &k("map"), || {
                    format!(
                        "stick–slip–separation maps are built from the exact single-harmonic cycle and need [harmonic_balance] harmonics = 1 (this case has {}); remove `map` for H > 1",
                        self.harmonic_balance.harmonics
                    )
                })?;
            }
            if let Some(hz) = &s.map_hz {
                self.require(s.map.is_some(), &k("map_hz"), || {
                    "maps at chosen frequencies need `map` (the number of phase angles)"
                })?;
                self.require(
                    !hz.is_empty() && hz.len() <= strip::MAX_MAP_FREQUENCIES,
                    &k("map_hz"),
                    || {
                        format!(
                            "give 1 to {} frequencies (found {})",
                            strip::MAX_MAP_FREQUENCIES,
                            hz.len()
                        )
                    },
                )?;
                for (j, &f) in hz.iter().enumerate() {
                    self.positive(&format!("{}[{j}]", k("map_hz")), f)?;
                }
            }
        }
        Ok(())
    }

    /// The keys of `e` fit its kind: every required key given, no key of another kind.
    pub(super) fn check_element_keys(&self, key: &str, e: &FrictionElement) -> Result<()> {
        let (required, optional) = e.kind.keys();
        let given = e.given_keys();
        let kind = e.kind.name();
        if let Some(k) = required.iter().find(|k| !given.contains(k)) {
            return Err(self.key_error(
                &KeyPath::parse(&format!("{key}.kind")),
                format!(
                    "an element of kind = \"{kind}\" needs the key `{k}` (its keys: {})",
                    required.join(", ")
                ),
            ));
        }
        if let Some(k) = given
            .iter()
            .find(|k| !required.contains(k) && !optional.contains(k))
        {
            return Err(self.key_error(
                &KeyPath::parse(&format!("{key}.{k}")),
                format!(
                    "`{k}` is not a key of kind = \"{kind}\" (its keys: {})",
                    required
                        .iter()
                        .chain(optional)
                        .copied()
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            ));
        }
        Ok(())
    }

    /// Ranges of the kind's parameters (the keys are known to be present).
    pub(super) fn check_element_values(&self, key: &str, e: &FrictionElement) -> Result<()> {
        let val = |v: Option<f64>| v.unwrap_or(0.0);
        match e.kind {
            ElementKind::Friction => self.check_friction(
                key,
                val(e.mu),
                val(e.kt),
                e.kn,
                val(e.n0),
                e.normal.is_some(),
            ),
            ElementKind::CubicSpring => self.finite(&format!("{key}.k3"), &[val(e.k3)]),
            ElementKind::PolynomialSpring => {
                let c = e.coefficients.as_deref().unwrap_or_default();
                let p = e.exponents.as_deref().unwrap_or_default();
                self.finite(&format!("{key}.coefficients"), c)?;
                self.require(!c.is_empty() && c.len() == p.len(), &format!("{key}.exponents"), || {
                    format!(
                        "`coefficients` ({} entries) and `exponents` ({} entries) must be non-empty lists of equal length",
                        c.len(),
                        p.len()
                    )
                })?;
                self.require(
                    p.iter().all(|&x| (1..=MAX_EXPONENT).contains(&x)),
                    &format!("{key}.exponents"),
                    || format!("exponents must be integers from 1 to {MAX_EXPONENT} (found {p:?})"),
                )
            }
            ElementKind::UnilateralSpring => {
                self.non_negative(&format!("{key}.k"), val(e.k))?;
                self.finite(&format!("{key}.gap"), &[val(e.gap)])
            }
            ElementKind::QuadraticDamper => self.finite(&format!("{key}.c"), &[val(e.c)]),
            ElementKind::TanhFriction => {
                self.non_negative(&format!("{key}.mu"), val(e.mu))?;
                self.non_negative(&format!("{key}.n0"), val(e.n0))?;
                self.positive(&format!("{key}.eps"), val(e.eps))
            }
        }
    }

    pub(super) fn check_weighted(&self, key: &str, w: &WeightedDofs) -> Result<()> {
        let ok = !w.dofs.is_empty() && w.dofs.len() == w.weights.len();
        self.require(ok, key, || {
            format!(
                "`dofs` ({} entries) and `weights` ({} entries) must be non-empty lists of equal length",
                w.dofs.len(),
                w.weights.len()
            )
        })?;
        self.finite(&format!("{key}.weights"), &w.weights)
    }

    pub(super) fn validate_harmonic_balance(&self) -> Result<()> {
        let hb = &self.harmonic_balance;
        let h = hb.harmonics;
        self.require(h >= 1, "harmonic_balance.harmonics", || {
            "needs at least 1 harmonic (the forcing is on harmonic 1)"
        })?;
        if let Some(m) = hb.modes {
            self.require(m >= 1, "harmonic_balance.modes", || {
                "needs at least 1 mode (or omit it to solve on the physical rows)"
            })?;
            self.require(self.kind() == CaseKind::Matrix, "harmonic_balance.modes", || {
                "modal coordinates are built for models on matrix rows ([[element]] or [[strip]] friction); a sector with [[contact]] interfaces or a [damper] is solved on its own coordinates: remove `modes`"
            })?;
        }
        let n = hb.samples();
        let default = HarmonicBalance {
            harmonics: h,
            time_samples: None,
            ..HarmonicBalance::default()
        }
        .samples();
        self.require(n >= 2 * h + 2, "harmonic_balance.time_samples", || {
            format!(
                "{n} samples cannot resolve {h} harmonics without aliasing; use at least 2H+2 = {} (or omit it for the default {default})",
                2 * h + 2
            )
        })
    }

    pub(super) fn validate_continuation(&self) -> Result<()> {
        let Some(c) = &self.continuation else {
            return Ok(());
        };
        let k = |name: &str| format!("continuation.{name}_{}", c.unit.suffix());
        self.positive(&k("start"), c.start)?;
        self.positive(&k("end"), c.end)?;
        self.positive(&k("step"), c.step)?;
        self.require(c.start != c.end, &k("end"), || {
            "the range is empty: end equals start"
        })?;
        if let Some(s) = c.min_step {
            self.positive(&k("min_step"), s)?;
        }
        if let Some(s) = c.max_step {
            self.positive(&k("max_step"), s)?;
        }
        if let (Some(lo), Some(hi)) = (c.min_step, c.max_step) {
            self.require(lo <= hi, &k("min_step"), || {
                format!("min step {lo} exceeds max step {hi}")
            })?;
        }
        if let Some(t) = c.tolerance {
            self.positive("continuation.tolerance", t)?;
        }
        self.require(c.max_points != Some(0), "continuation.max_points", || {
            "must be ≥ 1"
        })?;
        self.require(
            c.max_iterations != Some(0),
            "continuation.max_iterations",
            || "must be ≥ 1",
        )
    }

    pub(super) fn validate_march(&self) -> Result<()> {
        let Some(m) = &self.march else { return Ok(()) };
        self.positive(&format!("march.frequency_{}", m.unit.suffix()), m.frequency)?;
        self.require(m.periods >= 1, "march.periods", || "must be ≥ 1")?;
        self.require(m.steps_per_period >= 1, "march.steps_per_period", || {
            "must be ≥ 1"
        })?;
        if let Some(r) = m.step_ratio {
            self.require(
                r > 0.0 && r < std::f64::consts::FRAC_1_PI,
                "march.step_ratio",
                || format!("Δτ/𝕋 must satisfy 0 < r < 1/π ≈ 0.318, the convergence limit of Newmark's corrector (found {r})"),
            )?;
        }
        if let Some(dt) = m.time_step {
            self.positive("march.time_step_s", dt)?;
        }
        if let Some(t) = m.tolerance {
            self.positive("march.tolerance", t)?;
        }
        if let Some(t) = m.steady_tolerance {
            self.positive("march.steady_tolerance", t)?;
        }
        for (key, g) in [
            ("march.gamma", m.gamma),
            ("march.gamma_thermal", m.gamma_thermal),
        ] {
            if let Some(g) = g {
                self.require((0.5..=1.0).contains(&g), key, || {
                    format!("γ must lie in [1/2, 1], where the θ-method is unconditionally stable (found {g})")
                })?;
            }
        }
        if let Some(t) = m.activation_tolerance {
            self.non_negative("march.activation_tolerance", t)?;
        }
        Ok(())
    }

    pub(super) fn validate_damper(&self) -> Result<()> {
        let Some(d) = &self.damper else { return Ok(()) };
        self.positive("damper.mass", d.mass)?;
        self.positive("damper.inertia", d.inertia)?;
        self.non_negative("damper.centrifugal_force", d.centrifugal_force)?;
        self.non_negative("damper.damping_ratio", d.damping_ratio)?;
        self.require(d.damping_ratio < 1.0, "damper.damping_ratio", || {
            "must be below 1 (a modal damping ratio; 0.05 damps the damper's inner oscillation)"
        })?;
        self.require(!d.contact.is_empty(), "damper", || {
            "needs at least one [[damper.contact]]"
        })?;
        for (i, p) in d.platform.iter().enumerate() {
            let key = format!("damper.platform[{i}]");
            self.finite(&format!("{key}.amplitude"), &p.amplitude)?;
            self.finite(&format!("{key}.phase_deg"), &[p.phase_deg])?;
        }
        for (i, c) in d.contact.iter().enumerate() {
            let key = format!("damper.contact[{i}]");
            let known = d.platform.iter().any(|p| p.name == c.platform);
            self.require(known, &format!("{key}.platform"), || {
                let names: Vec<&str> = d.platform.iter().map(|p| p.name.as_str()).collect();
                format!(
                    "no [[damper.platform]] is named '{}'; the platforms are: {}",
                    c.platform,
                    names.join(", ")
                )
            })?;
            self.finite(&format!("{key}.point"), &c.point)?;
            self.finite(&format!("{key}.normal"), &c.normal)?;
            self.require(
                c.normal[0].hypot(c.normal[1]) > 0.0,
                &format!("{key}.normal"),
                || "the contact normal must not be zero",
            )?;
            self.check_friction(&key, c.mu, c.kt, c.kn, c.n0, true)?;
        }
        Ok(())
    }
}
