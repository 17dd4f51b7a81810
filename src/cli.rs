//! The command line (`docs/user-guide.md`, "Commands").
//!
//! Every command has `--help`; commands that report take `--json` and then print one JSON object
//! on stdout (logs and progress on stderr). Exit status: 0 success, 1 failed computation, 2 bad
//! input — see [`crate::error::Error::exit_code`].

use std::path::{Path, PathBuf};
use std::time::Instant;

use clap::{Args, Parser, Subcommand, ValueEnum};
use serde_json::{json, Value};

use crate::case::{Case, MarchScheme};
use crate::eigen::{lowest_modes, EigenOptions};
use crate::error::{Error, Result};
use crate::matrix_io::{write_dof_map, write_matrix_market_symmetric};
use crate::mesh::msh::read_msh;
use crate::mesh::Mesh;
use crate::model::{self, StructuralModel};
use crate::pipeline;
use crate::reduction::{hermitian_modes, Sector};
use crate::sama;

/// nlrom: vibration of structures with friction contacts (bladed disks with shroud,
/// underplatform and root joints) by reduced-order models and harmonic balance.
#[derive(Debug, Parser)]
#[command(name = "nlrom", version, about, long_about = None, propagate_version = true)]
pub struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Mesh utilities.
    #[command(subcommand)]
    Mesh(MeshCommand),
    /// Natural frequencies (Hz) of the model at a stage of the pipeline.
    Modes(ModesArgs),
    /// Write the assembled K, M (Matrix Market, symmetric) and the DOF map dofs.csv.
    Export(ExportArgs),
    /// Stage 2: build the reduced-order models for every harmonic index the case needs.
    Reduce(ReduceArgs),
    /// Stage 3: list the contact pairs (targets, weights, local frames, distances).
    Contact(ContactArgs),
    /// Stage 4: forced response by harmonic balance with continuation.
    Solve(SolveArgs),
    /// Time marching (Newmark variants, quasi-static).
    March(MarchArgs),
    /// All stages in order.
    Run(RunArgs),
    /// Many cases (or many meshes with one template case) in parallel.
    Batch(BatchArgs),
    /// Run the bundled demo case end to end.
    Demo(DemoArgs),
}

#[derive(Debug, Subcommand)]
enum MeshCommand {
    /// Format, node count, element counts by type, physical groups and bounding box of a Gmsh
    /// MSH file (2.2 or 4.1, ASCII or binary).
    Info(MeshInfoArgs),
}

#[derive(Debug, Args)]
struct MeshInfoArgs {
    /// The Gmsh .msh file.
    file: PathBuf,
    /// Print one JSON object on stdout.
    #[arg(long)]
    json: bool,
}

/// The stage of the pipeline whose model `modes` solves.
#[derive(Debug, Clone, Copy, ValueEnum)]
enum Stage {
    /// The assembled or imported model with clamps.
    Full,
    /// The Craig–Bampton model.
    Cb,
    /// Craig–Bampton + cyclic constraint for harmonic index K.
    Cs,
    /// After Gram–Schmidt interface reduction.
    Gsi,
}

#[derive(Debug, Args)]
struct ModesArgs {
    /// The case file (TOML).
    case: PathBuf,
    /// The stage of the pipeline.
    #[arg(long, value_enum, default_value = "full")]
    stage: Stage,
    /// Harmonic index K (stages cs and gsi).
    #[arg(long)]
    harmonic: Option<usize>,
    /// Number of modes.
    #[arg(long, default_value_t = 20)]
    num: usize,
    /// Shift the eigensolver to −(2π·F)² (F in Hz): required for a model without clamp
    /// (free–free, six rigid-body modes); a fraction of the first elastic frequency is a good F.
    #[arg(long, value_name = "F")]
    shift_hz: Option<f64>,
    /// Print one JSON object on stdout.
    #[arg(long)]
    json: bool,
}

#[derive(Debug, Args)]
struct ExportArgs {
    /// The case file (TOML).
    case: PathBuf,
    /// Output directory for K.mtx, M.mtx and dofs.csv.
    #[arg(long)]
    dir: PathBuf,
}

/// Log and progress options of the pipeline commands.
#[derive(Debug, Clone, Copy, Args)]
struct Verbosity {
    /// No progress bars and no log lines (warnings and errors are still printed).
    #[arg(short, long)]
    quiet: bool,
    /// Also print the stages' logs (model, reduction, contact pairs).
    #[arg(short, long)]
    verbose: bool,
}

impl Verbosity {
    fn reporter(self) -> crate::pipeline::Reporter {
        crate::pipeline::Reporter::new(self.quiet, self.verbose)
    }
}

#[derive(Debug, Args)]
struct ReduceArgs {
    /// The case file (TOML).
    case: PathBuf,
    /// The ROM file to write (HDF5).
    #[arg(short, long)]
    output: PathBuf,
    /// Print one JSON object on stdout.
    #[arg(long)]
    json: bool,
    #[command(flatten)]
    verbosity: Verbosity,
}

#[derive(Debug, Args)]
struct ContactArgs {
    /// The case file (TOML).
    case: PathBuf,
    /// Print one JSON object on stdout.
    #[arg(long)]
    json: bool,
}

#[derive(Debug, Args)]
struct SolveArgs {
    /// The case file (TOML).
    case: PathBuf,
    /// The result file to write (HDF5); default: the case's [output] file, else <case stem>.h5
    /// next to the case.
    #[arg(short, long)]
    output: Option<PathBuf>,
    /// Print one JSON summary on stdout (per sweep point: points, resonance_hz,
    /// peak_amplitude, q_factor).
    #[arg(long)]
    json: bool,
    /// Also compute the stability of every point (Hill's method; /frf/<i>/stable).
    #[arg(long)]
    stability: bool,
    #[command(flatten)]
    verbosity: Verbosity,
}

/// Time-marching schemes.
#[derive(Debug, Clone, Copy, ValueEnum)]
enum Scheme {
    /// Standard Newmark-β (β = 1/4, γ = 1/2).
    Newmark,
    /// Newmark with the time step adapted to the contact state.
    Adaptive,
    /// Piecewise-linear Newmark predictor–corrector.
    PiecewiseLinear,
    /// Piecewise-linear Newmark with the adaptive time step.
    AdaptivePiecewiseLinear,
    /// Quasi-static method for negligible inertia.
    QuasiStatic,
}

impl Scheme {
    /// The case schema's scheme.
    fn to_case(self) -> MarchScheme {
        match self {
            Scheme::Newmark => MarchScheme::Newmark,
            Scheme::Adaptive => MarchScheme::Adaptive,
            Scheme::PiecewiseLinear => MarchScheme::PiecewiseLinear,
            Scheme::AdaptivePiecewiseLinear => MarchScheme::AdaptivePiecewiseLinear,
            Scheme::QuasiStatic => MarchScheme::QuasiStatic,
        }
    }
}

#[derive(Debug, Args)]
struct MarchArgs {
    /// The case file (TOML).
    case: PathBuf,
    /// The result file to write (HDF5).
    #[arg(short, long)]
    output: PathBuf,
    /// The scheme (default: the case's [march] scheme).
    #[arg(long, value_enum)]
    scheme: Option<Scheme>,
    /// Print one JSON object on stdout (counts, histogram, wall time).
    #[arg(long)]
    json: bool,
}

#[derive(Debug, Args)]
struct RunArgs {
    /// The case file (TOML).
    case: PathBuf,
    /// The result file (default: the case's [output] file, else <case stem>.h5 next to the
    /// case). The ROM is kept in the case's [rom] file, else <result stem>.rom.h5 next to it,
    /// and reused while the mesh, material and reduction settings are unchanged.
    #[arg(short, long)]
    output: Option<PathBuf>,
    /// Print one JSON summary on stdout.
    #[arg(long)]
    json: bool,
    /// Also compute the stability of every point (Hill's method; /frf/<i>/stable).
    #[arg(long)]
    stability: bool,
    #[command(flatten)]
    verbosity: Verbosity,
}

#[derive(Debug, Args)]
struct BatchArgs {
    /// Case files, or meshes (.msh) with one template case (--case).
    #[arg(required = true)]
    inputs: Vec<PathBuf>,
    /// Number of cases run at once (threads of the pool).
    #[arg(long, default_value_t = 1)]
    jobs: usize,
    /// Output directory: <name>.h5 per input, ROM files, summary.csv.
    #[arg(long, default_value = "batch_out")]
    out: PathBuf,
    /// Template case for mesh inputs (its [model] mesh is replaced by each mesh).
    #[arg(long = "case", value_name = "TEMPLATE")]
    template: Option<PathBuf>,
    /// Print one JSON object on stdout instead of the table.
    #[arg(long)]
    json: bool,
    #[command(flatten)]
    verbosity: Verbosity,
}

#[derive(Debug, Args)]
struct DemoArgs {
    /// Output directory.
    #[arg(long, default_value = "demo_out")]
    out: PathBuf,
    /// Print one JSON summary on stdout.
    #[arg(long)]
    json: bool,
    #[command(flatten)]
    verbosity: Verbosity,
}

/// Parses the command line, runs the command and returns the exit status; errors go to stderr.
pub fn main() -> i32 {
    let cli = Cli::parse();
    match run(cli) {
        Ok(()) => 0,
        Err(e) => {
            eprintln!("error: {e}");
            e.exit_code()
        }
    }
}

fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Mesh(MeshCommand::Info(a)) => mesh_info(&a.file, a.json),
        Command::Modes(a) => modes(&a),
        Command::Export(a) => export(&a.case, &a.dir),
        Command::Reduce(a) => {
            pipeline::reduce_command(&a.case, &a.output, &a.verbosity.reporter(), a.json)
        }
        Command::Contact(a) => contact(&a.case, a.json),
        Command::Solve(a) => pipeline::solve_command(
            &a.case,
            a.output.as_deref(),
            false,
            a.stability,
            &a.verbosity.reporter(),
            a.json,
        ),
        Command::March(a) => march(&a),
        Command::Run(a) => pipeline::solve_command(
            &a.case,
            a.output.as_deref(),
            true,
            a.stability,
            &a.verbosity.reporter(),
            a.json,
        ),
        Command::Batch(a) => pipeline::batch::batch_command(
            &pipeline::batch::BatchOptions {
                inputs: a.inputs,
                jobs: a.jobs,
                out: a.out,
                template: a.template,
            },
            &a.verbosity.reporter(),
            a.json,
        ),
        Command::Demo(a) => pipeline::demo::demo_command(&a.out, &a.verbosity.reporter(), a.json),
    }
}

/// `nlrom mesh info`: prints the summary of a mesh as text or JSON.
fn mesh_info(path: &Path, as_json: bool) -> Result<()> {
    let start = Instant::now();
    let mesh = read_msh(path)?;
    if as_json {
        let mut report = mesh_summary(&mesh);
        report["wall_seconds"] = json!(start.elapsed().as_secs_f64());
        println!("{report}");
    } else {
        print!("{}", mesh_summary_text(path, &mesh));
    }
    Ok(())
}

/// The `mesh info` JSON object of `docs/user-guide.md`.
pub fn mesh_summary(mesh: &Mesh) -> Value {
    let elements: serde_json::Map<String, Value> = mesh
        .element_counts()
        .into_iter()
        .map(|(k, n)| (k.name().to_string(), json!(n)))
        .collect();
    let groups: Vec<Value> = mesh
        .groups
        .iter()
        .map(|g| {
            json!({
                "name": g.name,
                "dim": g.dim,
                "tag": g.tag,
                "elements": mesh.group_element_count(g),
                "nodes": mesh.group_node_indices(g).len(),
            })
        })
        .collect();
    json!({
        "format": mesh.format.version.as_str(),
        "binary": mesh.format.binary,
        "nodes": mesh.num_nodes(),
        "elements": elements,
        "groups": groups,
        "bbox": mesh.bbox(),
    })
}

/// The human-readable `mesh info` report.
fn mesh_summary_text(path: &Path, mesh: &Mesh) -> String {
    let mut s = format!(
        "{}\n  format   MSH {} {}{}\n  nodes    {}\n  elements {}\n",
        path.display(),
        mesh.format.version.as_str(),
        if mesh.format.binary {
            "binary"
        } else {
            "ASCII"
        },
        if mesh.format.big_endian {
            " (big-endian)"
        } else {
            ""
        },
        mesh.num_nodes(),
        mesh.num_elements()
    );
    for (kind, n) in mesh.element_counts() {
        s += &format!("    {:<10} {n}\n", kind.name());
    }
    s += &format!("  physical groups ({})\n", mesh.groups.len());
    s += &format!(
        "    {:<24} {:>3} {:>6} {:>9} {:>7}\n",
        "name", "dim", "tag", "elements", "nodes"
    );
    for g in &mesh.groups {
        s += &format!(
            "    {:<24} {:>3} {:>6} {:>9} {:>7}\n",
            g.name,
            g.dim,
            g.tag,
            mesh.group_element_count(g),
            mesh.group_node_indices(g).len()
        );
    }
    let [lo, hi] = mesh.bbox();
    s += &format!(
        "  bounding box [{:.6e}, {:.6e}, {:.6e}] .. [{:.6e}, {:.6e}, {:.6e}]\n",
        lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]
    );
    s
}

/// Progress lines on stderr.
fn log_stderr(line: &str) {
    eprintln!("nlrom: {line}");
}

/// Loads a case and builds its structural model, logging to stderr.
fn load_model(case_path: &Path) -> Result<(Case, StructuralModel)> {
    let case = Case::load(case_path)?;
    let model = model::build(&case, &mut log_stderr)?;
    Ok((case, model))
}

/// `nlrom modes`: natural frequencies of the model at a stage.
fn modes(a: &ModesArgs) -> Result<()> {
    let start = Instant::now();
    let stage = match a.stage {
        Stage::Full => "full",
        Stage::Cb | Stage::Cs | Stage::Gsi => return reduced_modes(a, start),
    };
    let shift = match a.shift_hz {
        Some(f) if f.is_finite() && f > 0.0 => -(2.0 * std::f64::consts::PI * f).powi(2),
        Some(f) => {
            return Err(Error::input(format!(
                "--shift-hz {f}: give a positive frequency in Hz"
            )))
        }
        None => 0.0,
    };
    let (_, model) = load_model(&a.case)?;
    let n = model.free.n_free();
    if a.num == 0 || a.num >= n {
        return Err(Error::input(format!(
            "--num {}: ask for 1 to {} modes (the model has {n} free DOF)",
            a.num,
            n.saturating_sub(1)
        )));
    }
    let opts = EigenOptions {
        shift,
        ..EigenOptions::default()
    };
    let t = Instant::now();
    let modes = lowest_modes(model.free.k.as_ref(), model.free.m.as_ref(), a.num, &opts).map_err(|e| {
        if shift == 0.0 && model.free.n_free() == model.n_dofs {
            Error::Compute(format!(
                "{e}\nThe model has no clamp: for a free–free model pass --shift-hz F (e.g. a tenth of the first elastic frequency), or clamp a group in [model] clamp"
            ))
        } else {
            e
        }
    })?;
    log_stderr(&format!(
        "{} modes in {:.2} s",
        modes.len(),
        t.elapsed().as_secs_f64()
    ));
    let report = ModesReport {
        stage,
        harmonic: a.harmonic,
        frequencies_hz: modes.frequencies_hz(),
        residuals: modes.residuals.clone(),
        dofs: n,
        extra: json!({}),
    };
    report.print(&a.case, a.json, start);
    Ok(())
}

/// What `nlrom modes` reports (the JSON keys of `docs/user-guide.md`).
struct ModesReport {
    stage: &'static str,
    harmonic: Option<usize>,
    frequencies_hz: Vec<f64>,
    residuals: Vec<f64>,
    dofs: usize,
    /// More keys for the JSON object (e.g. the GSI report).
    extra: Value,
}

impl ModesReport {
    /// Prints the report as one JSON object or as a table.
    fn print(&self, case: &Path, as_json: bool, start: Instant) {
        if as_json {
            let mut report = json!({
                "stage": self.stage,
                "harmonic": self.harmonic,
                "frequencies_hz": self.frequencies_hz,
                "residuals": self.residuals,
                "dofs": self.dofs,
            });
            if let (Some(obj), Some(extra)) = (report.as_object_mut(), self.extra.as_object()) {
                obj.extend(extra.clone());
            }
            report["wall_seconds"] = json!(start.elapsed().as_secs_f64());
            println!("{report}");
            return;
        }
        let harmonic = self
            .harmonic
            .map(|k| format!(", harmonic index {k}"))
            .unwrap_or_default();
        let what = if self.stage == "full" {
            "free DOF"
        } else {
            "reduced coordinates"
        };
        println!(
            "{} modes of {} (stage {}{harmonic}, {} {what})",
            self.frequencies_hz.len(),
            case.display(),
            self.stage,
            self.dofs
        );
        println!("{:>5} {:>16} {:>12}", "mode", "frequency (Hz)", "residual");
        for (i, (f, r)) in self.frequencies_hz.iter().zip(&self.residuals).enumerate() {
            println!("{:>5} {:>16.6} {:>12.2e}", i + 1, f, r);
        }
    }
}

/// `nlrom modes --stage cb|cs|gsi`: the Craig–Bampton model, CB + cyclic constraint for harmonic
/// index K, or CB + CS + GSI (`nlrom::reduction`). Residual: ‖Kx − λMx‖/‖Kx‖ of the dense
/// reduced problem.
fn reduced_modes(a: &ModesArgs, start: Instant) -> Result<()> {
    let case = Case::load(&a.case)?;
    let (stage, harmonic) = match a.stage {
        Stage::Cb => {
            if let Some(k) = a.harmonic {
                return Err(Error::input(format!(
                    "--harmonic {k}: the cb stage has no cyclic constraint; use --stage cs --harmonic {k}"
                )));
            }
            ("cb", None)
        }
        Stage::Cs => ("cs", Some(required_harmonic(a, &case, "cs")?)),
        _ => ("gsi", Some(required_harmonic(a, &case, "gsi")?)),
    };
    let gsi_modes = if stage == "gsi" {
        Some(
            case.reduction
                .as_ref()
                .and_then(|r| r.gsi_modes)
                .ok_or_else(|| {
                    Error::input(format!(
                        "{}: --stage gsi needs `[reduction] gsi_modes = N` in the case",
                        a.case.display()
                    ))
                })?,
        )
    } else {
        None
    };
    let model = model::build(&case, &mut log_stderr)?;
    let sector = Sector::build(&case, &model, &mut log_stderr)?;
    let h = match harmonic {
        None => sector.cb_model(),
        Some(k) => sector.harmonic(k, gsi_modes)?,
    };
    let n = h.dofs.len();
    if a.num == 0 || a.num > n {
        return Err(Error::input(format!(
            "--num {}: ask for 1 to {n} modes (the {stage} model has {n} coordinates)",
            a.num
        )));
    }
    let modes = hermitian_modes(h.stiffness.as_ref(), h.mass.as_ref(), h.real)?;
    let extra = match &h.gsi {
        Some(g) => {
            json!({"gsi": {"modes_used": g.modes_used, "retained": g.retained, "dropped": g.dropped}})
        }
        None => json!({}),
    };
    if let Some(g) = &h.gsi {
        log_stderr(&format!(
            "GSI: {} of {} frontier vectors retained, dropped {:?}",
            g.retained, g.modes_used, g.dropped
        ));
    }
    let report = ModesReport {
        stage,
        harmonic,
        frequencies_hz: modes.frequencies_hz(a.num),
        residuals: modes.residuals(h.stiffness.as_ref(), h.mass.as_ref(), a.num),
        dofs: n,
        extra,
    };
    report.print(&a.case, a.json, start);
    Ok(())
}

/// `--harmonic K` for the cs and gsi stages, which need a `[cyclic]` table.
fn required_harmonic(a: &ModesArgs, case: &Case, stage: &str) -> Result<usize> {
    if case.cyclic.is_none() {
        return Err(Error::input(format!(
            "{}: --stage {stage} needs a cyclic model (a [cyclic] table in the case)",
            a.case.display()
        )));
    }
    a.harmonic.ok_or_else(|| {
        Error::input(format!(
            "--stage {stage} needs --harmonic K (the harmonic index, 0 ≤ K < N)"
        ))
    })
}

/// `nlrom export`: K and M of the free (clamped) model as symmetric Matrix Market files and the
/// DOF map of their rows.
fn export(case_path: &Path, dir: &Path) -> Result<()> {
    let (_, model) = load_model(case_path)?;
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    write_matrix_market_symmetric(&dir.join("K.mtx"), &model.free.k)?;
    write_matrix_market_symmetric(&dir.join("M.mtx"), &model.free.m)?;
    let mut written = vec!["K.mtx", "M.mtx"];
    if let Some(map) = model.free_dof_map() {
        write_dof_map(&dir.join("dofs.csv"), &map)?;
        written.push("dofs.csv");
    }
    log_stderr(&format!(
        "wrote {} in {} ({} free DOF)",
        written.join(", "),
        dir.display(),
        model.free.n_free()
    ));
    Ok(())
}

/// `nlrom contact`: the contact pairs of every `[[contact]]` of the case (SAMA or node-to-node).
fn contact(case_path: &Path, as_json: bool) -> Result<()> {
    let start = Instant::now();
    let case = Case::load(case_path)?;
    if case.contact.is_empty() {
        return Err(Error::input(format!(
            "{}: the case has no [[contact]] table; add one with `contact`, `target`, `mu`, `kt`, `kn`, `n0` (see docs/case-file.md)",
            case_path.display()
        )));
    }
    let Some(mesh_path) = &case.model.mesh else {
        return Err(Error::input(format!(
            "{}: [[contact]] needs `model.mesh` (the groups and coordinates of the contact and target nodes)",
            case_path.display()
        )));
    };
    let mesh = read_msh(mesh_path)?;
    case.check_groups(&mesh)?;
    let cyclic = case
        .cyclic
        .as_ref()
        .map(crate::cyclic::CyclicGeometry::from_case)
        .transpose()?;
    let interfaces = sama::build_interfaces(&case, &mesh, cyclic.as_ref())?;
    for iface in &interfaces {
        log_stderr(&pipeline::solve::projection_line(iface));
        if let Some(w) = pipeline::solve::unprojected_warning(iface, "listed under \"unprojected\"")
        {
            log_stderr(&format!("warning: {w}"));
        }
    }
    if as_json {
        let list: Vec<Value> = interfaces
            .iter()
            .map(sama::report::interface_json)
            .collect();
        let report = json!({
            "interfaces": list,
            "wall_seconds": start.elapsed().as_secs_f64(),
        });
        println!("{report}");
    } else {
        print!("{}", sama::report::interfaces_text(&interfaces));
    }
    Ok(())
}

/// `nlrom march`: time marching of a `[damper]`, matrix-defined or sector ROM case; writes `/march/` and
/// reports the counts (steps, iterations per step, state changes, wall time).
fn march(a: &MarchArgs) -> Result<()> {
    use crate::march::march as run_march;
    use crate::pipeline::march_output::write_march_results;
    use crate::problem::march_case::case_march;
    let start = Instant::now();
    let case = Case::load(&a.case)?;
    let cm = case_march(&case, a.scheme.map(Scheme::to_case), &mut log_stderr)?;
    let out = run_march(&cm.system, &cm.settings)?;
    let info = crate::output::FileInfo {
        title: case.title.clone(),
        case_text: case.source_text.clone(),
    };
    write_march_results(&a.output, &info, &cm, &out)?;
    let last = out.periods.last();
    let report = json!({
        "scheme": out.scheme.as_str(),
        "steps": out.steps,
        "rejected_steps": out.rejected_steps,
        "total_iterations": out.total_iterations,
        "iteration_histogram": out.iteration_histogram(),
        "single_iteration_fraction": out.single_iteration_fraction(),
        "state_changes_last_period": last.map(|p| p.state_changes),
        "periodicity_error_last_period": last.and_then(|p| p.periodicity_error),
        "steady_period": out.steady_period,
        "time_step_range_s": [out.step_range.0, out.step_range.1],
        "first_harmonic_last_period": cm.response.iter().map(|&d| out.first_harmonic_amplitude()[d]).collect::<Vec<_>>(),
        "response_dofs": cm.response.iter().map(|&d| cm.system.dof_names[d].clone()).collect::<Vec<_>>(),
        "march_wall_seconds": out.wall_seconds,
        "output": a.output.display().to_string(),
        "wall_seconds": start.elapsed().as_secs_f64(),
    });
    if a.json {
        println!("{report}");
    } else {
        println!(
            "{} march of {}: {} steps ({} iterations, {:.1} % single-iteration steps), {} state changes in the last period, steady {}, {:.3} s; wrote {}",
            out.scheme,
            a.case.display(),
            out.steps,
            out.total_iterations,
            100.0 * out.single_iteration_fraction(),
            last.map_or(0, |p| p.state_changes),
            out.steady_period.map_or("not reached".to_string(), |p| format!("after {p} periods")),
            out.wall_seconds,
            a.output.display()
        );
    }
    Ok(())
}
