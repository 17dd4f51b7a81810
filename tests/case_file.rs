//! The TOML case file: the examples of docs/case-file.md parse, errors name the key and the line.

use std::path::{Path, PathBuf};

use nlrom::case::{
    Case, ContactElement, ContactModel, Damping, ExcitationLoad, FrequencyUnit, MarchScheme,
};
use nlrom::mesh::{ElementBlock, ElementType, Mesh, MshFormat, MshVersion, PhysicalGroup};
use nlrom::Error;

/// The full example of the founding case-file contract, verbatim (with `[response]` added).
const FULL: &str = r#"title = "shrouded sector, conforming shroud"

[model]
mesh = "sector.msh"
material = { young = 210e9, poisson = 0.33, density = 7800.0 }
clamp = ["hub"]                       # physical groups whose nodes are fixed
damping = { modal = 0.002 }           # or { rayleigh = [alpha, beta] }

[cyclic]                              # omit for a model without cyclic symmetry
sectors = 24
axis = { origin = [0.0, 0.0, 0.0], direction = [0.0, 0.0, 1.0] }
low = "left_frontier"
high = "right_frontier"

[reduction]
interface_modes = 30                  # CB fixed-interface modes
gsi_modes = 20                        # omit: keep all frontier DOF
keep = ["excitation"]                 # extra master nodes (response, excitation)

[[contact]]
name = "shroud"
contact = "shroud_contact"            # group of contact nodes
target = "shroud_target"              # group whose faces are the target surface
model = "sama"                        # "sama" | "node-to-node" (coincident nodes required)
element = "1d"                        # "1d": independent tangential directions | "2d": coupled
mu = 0.5
kt = 1.0e8                            # N/m per contact node
kn = 1.0e8                            # N/m per contact node
n0 = 113.0                            # N, total static normal preload, shared by tributary area
# misalignment = { translate = [0.0, 1.0e-4, 0.0] }   # static offset of the target face

[excitation]
engine_order = 3
group = "excitation"
force = [0.0, 0.0, 1.0]               # N per node, first harmonic

[response]
groups = ["excitation"]

[harmonic_balance]
harmonics = 3                         # H
time_samples = 64                     # optional

[continuation]
start_hz = 800.0
end_hz = 1400.0
step_hz = 2.0                         # initial step, adapted afterwards

[march]                               # time marching (nlrom march)
frequency_hz = 200.0                  # excitation frequency (or frequency_rad_s)
periods = 20
steps_per_period = 300                # the fixed step; the adaptive scheme starts from it
scheme = "piecewise-linear"           # newmark | adaptive | piecewise-linear | quasi-static

[sweep]                               # optional: one FRF per value
"contact.shroud.n0" = [50.0, 100.0, 113.0, 150.0, 200.0, 250.0, 300.0]

[output]
file = "results/shroud_conforming.h5"
"#;

/// The matrix-defined example of the case-file contract, completed with a frequency range.
const MATRIX: &str = r#"[model]
stiffness = "K.mtx"
mass = "M.mtx"
damping = { matrix = "D.mtx" }        # or modal / rayleigh as above

[excitation]
dofs = [1]                            # matrix rows (0-based)
force = [1.0]                         # N, f = force·cos(ωt) on those rows

[response]
dofs = [0, 1, 2]

[[element]]
kind = "friction"
tangential = { dofs = [0, 1], weights = [-1.0, 1.0] }   # u_t = Σ weights·q[dofs]
# normal = { dofs = [2], weights = [1.0] }              # optional
kt = 20.0
kn = 0.0
mu = 1.0
n0 = 1.0                              # without a normal direction the slip limit is mu·n0

[continuation]
start_rad_s = 0.5
end_rad_s = 2.0
step_rad_s = 0.01
"#;

/// The error message of a failed parse.
fn input_error(text: &str) -> String {
    match Case::from_str(text, Path::new("case.toml")) {
        Err(Error::Input(m)) => m,
        Err(e) => panic!("expected Error::Input, got {e:?}"),
        Ok(_) => panic!("expected an error for:\n{text}"),
    }
}

/// `MATRIX` with `old` replaced by `new` (which must occur).
fn matrix_with(old: &str, new: &str) -> String {
    assert!(MATRIX.contains(old), "{old}");
    MATRIX.replace(old, new)
}

/// `FULL` with `old` replaced by `new` (which must occur).
fn full_with(old: &str, new: &str) -> String {
    assert!(FULL.contains(old), "{old}");
    FULL.replace(old, new)
}

#[test]
fn full_example_loads_with_the_right_values() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("shroud.toml");
    std::fs::write(&path, FULL).unwrap();
    let case = Case::load(&path).unwrap();

    assert_eq!(case.title, "shrouded sector, conforming shroud");
    assert_eq!(case.source_text, FULL);
    assert_eq!(case.path, path);
    let m = &case.model;
    assert_eq!(
        m.mesh.as_deref(),
        Some(dir.path().join("sector.msh").as_path())
    );
    let mat = m.material.unwrap();
    assert_eq!((mat.young, mat.poisson, mat.density), (210e9, 0.33, 7800.0));
    assert_eq!(m.clamp, ["hub"]);
    assert_eq!(m.damping, Some(Damping::Modal(0.002)));
    assert!(m.stiffness.is_none() && m.mass.is_none() && m.dofs.is_none());

    let cyc = case.cyclic.as_ref().unwrap();
    assert_eq!(cyc.sectors, 24);
    assert_eq!(cyc.axis.direction, [0.0, 0.0, 1.0]);
    assert_eq!(
        (cyc.low.as_str(), cyc.high.as_str()),
        ("left_frontier", "right_frontier")
    );

    let red = case.reduction.as_ref().unwrap();
    assert_eq!((red.interface_modes, red.gsi_modes), (30, Some(20)));
    assert_eq!(red.keep, ["excitation"]);

    assert_eq!(case.contact.len(), 1);
    let c = &case.contact[0];
    assert_eq!(
        (c.name.as_str(), c.contact.as_str(), c.target.as_str()),
        ("shroud", "shroud_contact", "shroud_target")
    );
    assert_eq!(
        (c.model, c.element),
        (ContactModel::Sama, ContactElement::OneD)
    );
    assert_eq!((c.mu, c.kt, c.kn, c.n0), (0.5, 1.0e8, 1.0e8, 113.0));
    assert!(c.misalignment.is_none());

    let ex = case.excitation.as_ref().unwrap();
    assert_eq!(ex.engine_order, Some(3));
    assert_eq!(ex.force_scale, 1.0);
    assert_eq!(
        ex.load,
        ExcitationLoad::Group {
            group: "excitation".into(),
            force: [0.0, 0.0, 1.0]
        }
    );
    assert_eq!(case.response.as_ref().unwrap().groups, ["excitation"]);

    assert_eq!(case.harmonic_balance.harmonics, 3);
    assert_eq!(case.harmonic_balance.samples(), 64);

    let cont = case.continuation.as_ref().unwrap();
    assert_eq!(cont.unit, FrequencyUnit::Hz);
    let (w0, w1, dw) = cont.omega_range();
    let two_pi = 2.0 * std::f64::consts::PI;
    assert_eq!(
        (w0, w1, dw),
        (two_pi * 800.0, two_pi * 1400.0, two_pi * 2.0)
    );

    let march = case.march.as_ref().unwrap();
    assert_eq!(march.omega(), two_pi * 200.0);
    assert_eq!((march.periods, march.steps_per_period), (20, 300));
    assert_eq!(march.scheme, MarchScheme::PiecewiseLinear);

    assert_eq!(case.sweep["contact.shroud.n0"].len(), 7);
    assert_eq!(
        case.output.as_ref().unwrap().file,
        dir.path().join("results/shroud_conforming.h5")
    );
    assert!(case.rom.is_none() && case.element.is_empty());
    assert!(case.sweep_point.is_none());
}

#[test]
fn contact_evaluation_analytic_parses_at_one_harmonic() {
    let text = full_with("n0 = 113.0 ", "n0 = 113.0\nevaluation = \"analytic\"\n")
        .replace("harmonics = 3 ", "harmonics = 1 ");
    let case = Case::from_str(&text, Path::new("case.toml")).unwrap();
    assert_eq!(
        case.contact[0].evaluation,
        nlrom::case::Evaluation::Analytic
    );
}

#[test]
fn matrix_example_parses() {
    let case = Case::from_str(MATRIX, Path::new("/cases/chain/case.toml")).unwrap();
    assert_eq!(case.title, "case");
    let m = &case.model;
    assert_eq!(
        m.stiffness.as_deref(),
        Some(Path::new("/cases/chain/K.mtx"))
    );
    assert_eq!(m.mass.as_deref(), Some(Path::new("/cases/chain/M.mtx")));
    assert_eq!(
        m.damping,
        Some(Damping::Matrix(PathBuf::from("/cases/chain/D.mtx")))
    );
    assert!(m.mesh.is_none() && case.cyclic.is_none());

    let ex = case.excitation.as_ref().unwrap();
    assert_eq!(ex.engine_order, None);
    assert_eq!(
        ex.load,
        ExcitationLoad::Dofs {
            dofs: vec![1],
            force: vec![1.0]
        }
    );
    assert_eq!(case.response.as_ref().unwrap().dofs, [0, 1, 2]);

    assert_eq!(case.element.len(), 1);
    let e = &case.element[0];
    assert_eq!(e.tangential.dofs, [0, 1]);
    assert_eq!(e.tangential.weights, [-1.0, 1.0]);
    assert!(e.normal.is_none());
    assert_eq!(
        (e.kt, e.kn, e.mu, e.n0),
        (Some(20.0), 0.0, Some(1.0), Some(1.0))
    );

    // defaults: one harmonic, AFT samples = smallest power of two >= 4(H+1) = 8
    assert_eq!(case.harmonic_balance.harmonics, 1);
    assert_eq!(case.harmonic_balance.samples(), 8);
    let cont = case.continuation.as_ref().unwrap();
    assert_eq!(cont.unit, FrequencyUnit::RadPerSecond);
    assert_eq!(cont.omega_range(), (0.5, 2.0, 0.01));
    let points = case.sweep_points().unwrap();
    assert_eq!(points.len(), 1);
    assert_eq!(points[0].sweep_point.as_ref().unwrap().index, 0);
    assert!(points[0].sweep_point.as_ref().unwrap().values.is_empty());
}

#[test]
fn misspelt_key_names_the_key_path_and_the_line() {
    let msg = input_error(&full_with("mu = 0.5", "muu = 0.5"));
    assert!(
        msg.starts_with("case.toml: line 26, column 1: key 'contact[0]"),
        "{msg}"
    );
    assert!(msg.contains("muu"), "{msg}");

    let msg = input_error(&full_with("young = 210e9", "youngs = 210e9"));
    assert!(msg.starts_with("case.toml: line 5, "), "{msg}");
    assert!(msg.contains("key 'model.material"), "{msg}");
    assert!(msg.contains("youngs"), "{msg}");

    let msg = input_error(&full_with("[harmonic_balance]", "[harmonic_balanse]"));
    assert!(msg.starts_with("case.toml: line 40, "), "{msg}");
    assert!(msg.contains("harmonic_balanse"), "{msg}");
}

#[test]
fn wrong_type_names_the_key_and_line() {
    let msg = input_error(&full_with("sectors = 24", "sectors = \"24\""));
    assert!(
        msg.starts_with("case.toml: line 10, column 11: key 'cyclic.sectors'"),
        "{msg}"
    );
}

#[test]
fn toml_syntax_error_names_line_and_column() {
    let msg = input_error(&full_with("periods = 20", "periods = = 20"));
    assert!(msg.starts_with("case.toml: line 51, column "), "{msg}");
}

#[test]
fn negative_mu_names_contact_0_mu() {
    let msg = input_error(&full_with("mu = 0.5", "mu = -1.0"));
    assert_eq!(
        msg,
        "case.toml: line 26: key 'contact[0].mu': must be a finite number ≥ 0 (found -1)"
    );
}

#[test]
fn value_range_errors_name_their_keys() {
    let cases = [
        (
            full_with("poisson = 0.33", "poisson = 0.5"),
            "model.material.poisson",
        ),
        (
            full_with("young = 210e9", "young = 0.0"),
            "model.material.young",
        ),
        (full_with("sectors = 24", "sectors = 1"), "cyclic.sectors"),
        (
            full_with("time_samples = 64", "time_samples = 7"),
            "harmonic_balance.time_samples",
        ),
        (
            full_with("harmonics = 3 ", "harmonics = 0 "),
            "harmonic_balance.harmonics",
        ),
        (
            full_with("start_hz = 800.0", "start_hz = -800.0"),
            "continuation.start_hz",
        ),
        (
            full_with("step_hz = 2.0", "step_hz = 0.0"),
            "continuation.step_hz",
        ),
        (full_with("periods = 20", "periods = 0"), "march.periods"),
        (full_with("kt = 1.0e8", "kt = -1.0e8"), "contact[0].kt"),
        (
            full_with("modal = 0.002", "modal = 1.5"),
            "model.damping.modal",
        ),
        (
            matrix_with("weights = [-1.0, 1.0]", "weights = [-1.0]"),
            "element[0].tangential",
        ),
        (
            full_with(
                "model = \"sama\"  ",
                "model = \"node-to-node\"\ncoupling = \"interpolated\"\n",
            ),
            "contact[0].coupling",
        ),
        // the exact cycle needs the 1-D element
        (
            full_with("n0 = 113.0 ", "n0 = 113.0\nevaluation = \"analytic\"\n")
                .replace("harmonics = 3 ", "harmonics = 1 ")
                .replace("element = \"1d\"", "element = \"2d\""),
            "contact[0].evaluation",
        ),
    ];
    for (text, key) in cases {
        let msg = input_error(&text);
        assert!(msg.contains(&format!("key '{key}'")), "{key}: {msg}");
        assert!(msg.starts_with("case.toml: line "), "{key}: {msg}");
    }
}

#[test]
fn time_samples_below_2h_plus_2_is_rejected() {
    // H = 3 needs >= 8 samples: 8 is accepted, 7 is not
    Case::from_str(
        &full_with("time_samples = 64", "time_samples = 8"),
        Path::new("c.toml"),
    )
    .unwrap();
    let msg = input_error(&full_with("time_samples = 64", "time_samples = 7"));
    assert!(msg.contains("2H+2 = 8"), "{msg}");
}

#[test]
fn hz_and_rad_s_together_are_an_error() {
    let msg = input_error(&full_with(
        "step_hz = 2.0",
        "step_hz = 2.0\nend_rad_s = 9000.0",
    ));
    assert!(msg.contains("key 'continuation'"), "{msg}");
    assert!(msg.contains("_hz") && msg.contains("_rad_s"), "{msg}");
    assert!(msg.starts_with("case.toml: line 44, "), "{msg}");
}

#[test]
fn incomplete_frequency_range_is_an_error() {
    let msg = input_error(&full_with("step_hz = 2.0", ""));
    assert!(msg.contains("missing `step_hz`"), "{msg}");
}

#[test]
fn damping_needs_exactly_one_kind() {
    let msg = input_error(&full_with(
        "{ modal = 0.002 }",
        "{ modal = 0.002, rayleigh = [1.0, 1e-6] }",
    ));
    assert!(msg.contains("key 'model.damping'"), "{msg}");
    assert!(msg.contains("exactly one of"), "{msg}");
    let rayleigh = full_with("{ modal = 0.002 }", "{ rayleigh = [1.0, 1e-6] }");
    let case = Case::from_str(&rayleigh, Path::new("c.toml")).unwrap();
    assert_eq!(
        case.model.damping,
        Some(Damping::Rayleigh {
            alpha: 1.0,
            beta: 1e-6
        })
    );
}

#[test]
fn excitation_must_be_group_and_3_forces_or_equal_lists() {
    let msg = input_error(&full_with("force = [0.0, 0.0, 1.0]", "force = [0.0, 1.0]"));
    assert!(
        msg.contains("key 'excitation'") && msg.contains("2 values"),
        "{msg}"
    );
    let msg = input_error(&matrix_with("force = [1.0]", "force = [1.0, 2.0]"));
    assert!(msg.contains("`dofs` has 1 entries and `force` 2"), "{msg}");
}

#[test]
fn model_needs_mesh_or_both_matrices() {
    let msg = input_error(&matrix_with("mass = \"M.mtx\"\n", ""));
    assert!(
        msg.contains("key 'model.stiffness'") && msg.contains("`mass`"),
        "{msg}"
    );
    let msg = input_error("[model]\nclamp = []\n");
    assert!(msg.contains("key 'model'") && msg.contains("mesh"), "{msg}");
}

#[test]
fn duplicate_contact_names_are_rejected() {
    let second = "[[contact]]\nname = \"shroud\"\ncontact = \"a\"\ntarget = \"b\"\nmu = 0.1\nkt = 1.0\nkn = 1.0\nn0 = 1.0\n";
    let msg = input_error(&format!("{FULL}\n{second}"));
    assert!(
        msg.contains("key 'contact[1].name'") && msg.contains("used twice"),
        "{msg}"
    );
}

#[test]
fn sweep_gives_seven_points_with_the_n0_values() {
    let case = Case::from_str(FULL, Path::new("c.toml")).unwrap();
    let points = case.sweep_points().unwrap();
    let n0: Vec<f64> = points.iter().map(|p| p.contact[0].n0).collect();
    assert_eq!(n0, [50.0, 100.0, 113.0, 150.0, 200.0, 250.0, 300.0]);
    for (i, p) in points.iter().enumerate() {
        let sp = p.sweep_point.as_ref().unwrap();
        assert_eq!(sp.index, i);
        assert_eq!(sp.values, vec![("contact.shroud.n0".to_string(), n0[i])]);
        assert!(p.sweep.is_empty());
        assert_eq!(p.contact[0].mu, 0.5);
    }
}

#[test]
fn zipped_sweep_of_several_parameters() {
    let text = matrix_with(
        "[continuation]",
        "[sweep]\n\"element.0.mu\" = [0.1, 0.2]\n\"excitation.force_scale\" = [1.0, 3.0]\n\n[continuation]",
    );
    let case = Case::from_str(&text, Path::new("c.toml")).unwrap();
    let points = case.sweep_points().unwrap();
    assert_eq!(points.len(), 2);
    assert_eq!(points[1].element[0].mu, Some(0.2));
    assert_eq!(points[1].excitation.as_ref().unwrap().force_scale, 3.0);
    assert_eq!(
        points[1].sweep_point.as_ref().unwrap().values,
        vec![
            ("element.0.mu".to_string(), 0.2),
            ("excitation.force_scale".to_string(), 3.0)
        ]
    );

    let unequal = text.replace("[1.0, 3.0]", "[1.0, 3.0, 4.0]");
    let msg = input_error(&unequal);
    assert!(msg.contains("equal lengths"), "{msg}");
}

#[test]
fn unknown_sweep_path_is_named_with_the_valid_ones() {
    let msg = input_error(&full_with("\"contact.shroud.n0\"", "\"contact.shrud.n0\""));
    assert!(
        msg.contains("unknown sweep parameter 'contact.shrud.n0'"),
        "{msg}"
    );
    assert!(msg.contains("contact.shroud.n0"), "{msg}");
    assert!(msg.contains("model.damping.modal"), "{msg}");
    assert!(
        msg.starts_with("case.toml: line 56: key 'sweep.\"contact.shrud.n0\"'"),
        "{msg}"
    );
}

#[test]
fn invalid_sweep_value_names_the_point() {
    // n0 < 0 is an initial gap, allowed with kn > 0 ...
    let gap = full_with("[50.0, 100.0", "[50.0, -100.0");
    let case = Case::from_str(&gap, Path::new("c.toml")).unwrap();
    assert_eq!(case.sweep_points().unwrap()[1].contact[0].n0, -100.0);
    // ... but not with kn = 0, and a negative mu never
    let no_kn = gap.replace("kn = 1.0e8", "kn = 0.0");
    let msg = input_error(&no_kn);
    assert!(
        msg.starts_with("case.toml: line 56: key 'sweep.\"contact.shroud.n0\"[1]': sweep point 1 (contact.shroud.n0 = -100) is invalid"),
        "{msg}"
    );
    assert!(
        msg.contains("contact[0].n0") && msg.contains("kn > 0"),
        "{msg}"
    );
    let bad_mu = full_with(
        "\"contact.shroud.n0\" = [50.0, 100.0, 113.0, 150.0, 200.0, 250.0, 300.0]",
        "\"contact.shroud.mu\" = [0.1, -0.2]",
    );
    let msg = input_error(&bad_mu);
    assert!(
        msg.contains("sweep point 1") && msg.contains("contact[0].mu"),
        "{msg}"
    );
}

/// A small mesh: one tetra in volume "body", one triangle in each named surface group.
fn small_mesh(names: &[&str]) -> Mesh {
    let mut groups = vec![PhysicalGroup {
        name: "body".into(),
        dim: 3,
        tag: 1,
    }];
    let mut blocks = vec![ElementBlock {
        kind: ElementType::Tetra4,
        entity: 1,
        physicals: vec![1],
        tags: vec![1].into(),
        connectivity: vec![0, 1, 2, 3],
    }];
    for (i, n) in names.iter().enumerate() {
        let tag = 10 + i as i32;
        groups.push(PhysicalGroup {
            name: n.to_string(),
            dim: 2,
            tag,
        });
        blocks.push(ElementBlock {
            kind: ElementType::Triangle3,
            entity: tag,
            physicals: vec![tag],
            tags: vec![2 + i as u64].into(),
            connectivity: vec![0, 1, 2],
        });
    }
    Mesh {
        source: Some(PathBuf::from("sector.msh")),
        format: MshFormat {
            version: MshVersion::V41,
            binary: false,
            big_endian: false,
        },
        node_tags: vec![1, 2, 3, 4],
        coords: vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
        blocks,
        groups,
        periodic: vec![],
    }
}

#[test]
fn check_groups_accepts_a_complete_mesh() {
    let case = Case::from_str(FULL, Path::new("c.toml")).unwrap();
    let all = [
        "hub",
        "left_frontier",
        "right_frontier",
        "excitation",
        "shroud_contact",
        "shroud_target",
    ];
    case.check_groups(&small_mesh(&all)).unwrap();
}

#[test]
fn check_groups_names_the_key_and_the_missing_group() {
    let case = Case::from_str(FULL, Path::new("c.toml")).unwrap();
    let mesh = small_mesh(&[
        "hub",
        "left_frontier",
        "right_frontier",
        "excitation",
        "shroud_contact",
        "shroud_targets",
    ]);
    let msg = match case.check_groups(&mesh) {
        Err(Error::Input(m)) => m,
        other => panic!("{other:?}"),
    };
    assert!(
        msg.starts_with("c.toml: line 23: key 'contact[0].target': the mesh sector.msh has no physical group 'shroud_target'; did you mean 'shroud_targets'?"),
        "{msg}"
    );
    assert!(msg.contains("'hub' (dim 2, tag 10, 1 elements)"), "{msg}");
    assert!(msg.contains("'body' (dim 3, tag 1, 1 elements)"), "{msg}");
    assert_eq!(msg.lines().count(), 2, "{msg}");
}

#[test]
fn check_groups_reports_every_missing_group() {
    let case = Case::from_str(FULL, Path::new("c.toml")).unwrap();
    let msg = case
        .check_groups(&small_mesh(&["hub"]))
        .unwrap_err()
        .to_string();
    for key in [
        "cyclic.low",
        "cyclic.high",
        "reduction.keep[0]",
        "contact[0].contact",
        "contact[0].target",
        "excitation.group",
        "response.groups[0]",
    ] {
        assert!(msg.contains(&format!("key '{key}'")), "{key}: {msg}");
    }
    assert!(!msg.contains("model.clamp"), "{msg}");
}

#[test]
fn material_group_must_be_a_volume() {
    let text = full_with("clamp = [\"hub\"]", "clamp = [\"hub\"]\nmaterials = [{ group = \"hub\", young = 1e9, poisson = 0.3, density = 1000.0 }]");
    let case = Case::from_str(&text, Path::new("c.toml")).unwrap();
    let all = [
        "hub",
        "left_frontier",
        "right_frontier",
        "excitation",
        "shroud_contact",
        "shroud_target",
    ];
    let msg = case
        .check_groups(&small_mesh(&all))
        .unwrap_err()
        .to_string();
    assert!(
        msg.contains("key 'model.materials[0].group'") && msg.contains("dim 3"),
        "{msg}"
    );
}

#[test]
fn march_scheme_parses_from_the_command_line_spelling() {
    assert_eq!(
        "quasi-static".parse::<MarchScheme>(),
        Ok(MarchScheme::QuasiStatic)
    );
    assert!("implicit"
        .parse::<MarchScheme>()
        .unwrap_err()
        .contains("newmark"));
    assert_eq!(MarchScheme::PiecewiseLinear.to_string(), "piecewise-linear");
}
