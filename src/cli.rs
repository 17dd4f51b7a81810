//! The command line (`docs/user-guide.md`, "Commands"): the clap definitions of the commands
//! and the dispatch to [`crate::commands`], which implements them.
//!
//! Every command has `--help`; commands that report take `--json` and then print one JSON object
//! on stdout (logs and progress on stderr). Exit status: 0 success, 1 failed computation, 2 bad
//! input — see [`crate::error::Error::exit_code`].

use std::path::PathBuf;

use clap::builder::{PossibleValuesParser, TypedValueParser};
use clap::{Args, Parser, Subcommand};

use crate::case::{Evaluation, MarchScheme};
use crate::commands::modes::{ModesOptions, Stage};
use crate::commands::{self, Reporter};
use crate::error::Result;

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
    /// One friction contact point under a prescribed harmonic relative motion: force and
    /// normal-force harmonics, energy per cycle, regime, transition angles, hysteresis loop.
    Law(LawArgs),
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
    #[command(flatten)]
    verbosity: Verbosity,
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
    #[command(flatten)]
    verbosity: Verbosity,
}

#[derive(Debug, Args)]
struct ExportArgs {
    /// The case file (TOML).
    case: PathBuf,
    /// Output directory for K.mtx, M.mtx and dofs.csv.
    #[arg(long)]
    dir: PathBuf,
    #[command(flatten)]
    verbosity: Verbosity,
}

/// Log and progress options of every command.
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
    fn reporter(self) -> Reporter {
        Reporter::new(self.quiet, self.verbose)
    }
}

/// `--scheme`: the spellings of [`MarchScheme::as_str`], parsed by its `FromStr`.
fn scheme_parser() -> impl TypedValueParser<Value = MarchScheme> {
    PossibleValuesParser::new(MarchScheme::ALL.map(MarchScheme::as_str))
        .try_map(|s| s.parse::<MarchScheme>())
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
    #[command(flatten)]
    verbosity: Verbosity,
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

#[derive(Debug, Args)]
struct MarchArgs {
    /// The case file (TOML).
    case: PathBuf,
    /// The result file to write (HDF5).
    #[arg(short, long)]
    output: PathBuf,
    /// The scheme (default: the case's [march] scheme).
    #[arg(long, value_parser = scheme_parser())]
    scheme: Option<MarchScheme>,
    /// Print one JSON object on stdout (counts, histogram, wall time).
    #[arg(long)]
    json: bool,
    #[command(flatten)]
    verbosity: Verbosity,
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
#[command(args_conflicts_with_subcommands = true, subcommand_negates_reqs = true)]
struct BatchArgs {
    #[command(subcommand)]
    action: Option<BatchAction>,
    /// Case files, or meshes (.msh) with one template case (--case).
    #[arg(required = true)]
    inputs: Vec<PathBuf>,
    /// Number of cases run at once (threads of the pool).
    #[arg(long, default_value_t = 1)]
    jobs: usize,
    /// Output directory: <name>.h5 per input, summary.csv, the batch's records.
    #[arg(long, default_value = "batch_out")]
    out: PathBuf,
    /// Template case for mesh inputs (its [model] mesh is replaced by each mesh).
    #[arg(long = "case", value_name = "TEMPLATE")]
    template: Option<PathBuf>,
    /// Content-addressed ROM cache directory, shared by the cases (and by the array tasks of a
    /// cluster job: put it on a shared file system) [default: OUT/rom-cache].
    #[arg(long, value_name = "DIR")]
    rom_cache: Option<PathBuf>,
    /// Run only the I-th of N parts of the batch (case p goes to part p mod N + 1); gather the
    /// parts with `nlrom batch merge OUT`.
    #[arg(long, value_name = "I/N", conflicts_with = "slurm")]
    shard: Option<commands::batch::shard::Shard>,
    /// Run only the cases whose results are missing or failed (with --slurm: submit only the
    /// array tasks that have such cases).
    #[arg(long)]
    resume: bool,
    /// Write a Slurm job array script (OUT/slurm/nlrom-batch.sh), one shard per array task.
    #[arg(long)]
    slurm: bool,
    /// Number of array tasks (shards) [default: one per case, at most 100].
    #[arg(long, value_name = "N", requires = "slurm")]
    array_size: Option<usize>,
    /// Slurm partition (#SBATCH --partition).
    #[arg(long, value_name = "P", requires = "slurm")]
    partition: Option<String>,
    /// Slurm time limit per array task (#SBATCH --time), e.g. 2:00:00.
    #[arg(long, value_name = "T", requires = "slurm")]
    time: Option<String>,
    /// CPUs per array task (#SBATCH --cpus-per-task; the task's --jobs) [default: 1].
    #[arg(long, value_name = "C", requires = "slurm")]
    cpus: Option<usize>,
    /// Submit the script with sbatch and print the job id.
    #[arg(long, requires = "slurm")]
    submit: bool,
    /// Print one JSON object on stdout instead of the table.
    #[arg(long)]
    json: bool,
    #[command(flatten)]
    verbosity: Verbosity,
}

#[derive(Debug, Subcommand)]
enum BatchAction {
    /// Gather the records of a batch's shards into OUT/summary.csv (as a local batch writes it),
    /// list missing and failed cases, report wall and CPU time per case and per shard.
    Merge(MergeArgs),
}

#[derive(Debug, Args)]
struct MergeArgs {
    /// The batch's output directory (--out).
    dir: PathBuf,
    /// Print one JSON object on stdout.
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

#[derive(Debug, Args)]
struct LawArgs {
    /// A TOML file with any of the keys kt, kn, mu, n0, u, v, slider, evaluation,
    /// time_samples (the options below override it).
    #[arg(long, value_name = "FILE")]
    input: Option<PathBuf>,
    /// Tangential stiffness k_t (N/m).
    #[arg(long, allow_negative_numbers = true)]
    kt: Option<f64>,
    /// Normal stiffness k_n (N/m); default 0.
    #[arg(long, allow_negative_numbers = true)]
    kn: Option<f64>,
    /// Friction coefficient μ.
    #[arg(long, allow_negative_numbers = true)]
    mu: Option<f64>,
    /// Static normal load n0 (N); negative: an initial gap −n0/k_n.
    #[arg(long, allow_negative_numbers = true)]
    n0: Option<f64>,
    /// Tangential relative displacement U0,ReU1,ImU1[,ReU2,ImU2,…] (m):
    /// u(τ) = U0 + Σ (Re Un cos nτ − Im Un sin nτ).
    #[arg(
        long,
        value_delimiter = ',',
        allow_negative_numbers = true,
        value_name = "U0,RE1,IM1"
    )]
    u: Option<Vec<f64>>,
    /// Normal approach V0,ReV1,ImV1[,…] (m; v > 0 loads the contact); default none.
    #[arg(
        long,
        value_delimiter = ',',
        allow_negative_numbers = true,
        value_name = "V0,RE1,IM1"
    )]
    v: Option<Vec<f64>>,
    /// Slider position at τ = 0 before the first period (m); default 0.
    #[arg(long, allow_negative_numbers = true)]
    slider: Option<f64>,
    /// `analytic`: the exact single-harmonic cycle (default, H = 1); `aft`: the time-discrete law
    /// over N_t samples (any H).
    #[arg(long, value_parser = evaluation_parser())]
    evaluation: Option<Evaluation>,
    /// AFT samples per period N_t (default 1024).
    #[arg(long)]
    time_samples: Option<usize>,
    /// Write the hysteresis loop samples (tau_rad, u, v, f, n, w, state) to this CSV file
    /// (plot: tools/post/plot_law.py).
    #[arg(long = "loop", value_name = "FILE.csv")]
    loop_csv: Option<PathBuf>,
    /// Samples of the loop of the analytic evaluation (default 256).
    #[arg(long)]
    loop_samples: Option<usize>,
    /// Print one JSON object on stdout.
    #[arg(long)]
    json: bool,
    #[command(flatten)]
    verbosity: Verbosity,
}

/// `--evaluation`: `analytic` or `aft`.
fn evaluation_parser() -> impl TypedValueParser<Value = Evaluation> {
    PossibleValuesParser::new(["analytic", "aft"]).map(|s| match s.as_str() {
        "aft" => Evaluation::Aft,
        _ => Evaluation::Analytic,
    })
}

/// Parses the command line, runs the command and returns the exit status; errors go to stderr.
pub fn main() -> i32 {
    crate::problem::use_one_heap_arena();
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
        Command::Mesh(MeshCommand::Info(a)) => {
            commands::mesh_info_command(&a.file, &a.verbosity.reporter(), a.json)
        }
        Command::Modes(a) => commands::modes_command(
            &ModesOptions {
                case: a.case,
                stage: a.stage,
                harmonic: a.harmonic,
                num: a.num,
                shift_hz: a.shift_hz,
            },
            &a.verbosity.reporter(),
            a.json,
        ),
        Command::Export(a) => commands::export_command(&a.case, &a.dir, &a.verbosity.reporter()),
        Command::Reduce(a) => {
            commands::reduce_command(&a.case, &a.output, &a.verbosity.reporter(), a.json)
        }
        Command::Contact(a) => commands::contact_command(&a.case, &a.verbosity.reporter(), a.json),
        Command::Solve(a) => commands::solve_command(
            &a.case,
            a.output.as_deref(),
            false,
            a.stability,
            &a.verbosity.reporter(),
            a.json,
        ),
        Command::March(a) => commands::march_command(
            &a.case,
            &a.output,
            a.scheme,
            &a.verbosity.reporter(),
            a.json,
        ),
        Command::Run(a) => commands::solve_command(
            &a.case,
            a.output.as_deref(),
            true,
            a.stability,
            &a.verbosity.reporter(),
            a.json,
        ),
        Command::Batch(a) => batch(a),
        Command::Demo(a) => commands::demo_command(&a.out, &a.verbosity.reporter(), a.json),
        Command::Law(a) => commands::law::law_command(
            a.input.as_deref(),
            commands::law::LawInput {
                kt: a.kt,
                kn: a.kn,
                mu: a.mu,
                n0: a.n0,
                u: a.u,
                v: a.v,
                slider: a.slider,
                evaluation: a.evaluation,
                time_samples: a.time_samples,
            },
            &commands::law::LawOptions {
                loop_csv: a.loop_csv,
                loop_samples: a.loop_samples,
            },
            &a.verbosity.reporter(),
            a.json,
        ),
    }
}

/// `nlrom batch`: a local batch or shard, the Slurm script (`--slurm`), or `merge`.
fn batch(a: BatchArgs) -> Result<()> {
    if let Some(BatchAction::Merge(m)) = a.action {
        return commands::batch::merge::merge_command(&m.dir, &m.verbosity.reporter(), m.json);
    }
    let opts = commands::batch::BatchOptions {
        inputs: a.inputs,
        jobs: a.jobs,
        out: a.out,
        template: a.template,
        rom_cache: a.rom_cache,
        shard: a.shard,
        resume: a.resume,
    };
    let rep = a.verbosity.reporter();
    if a.slurm {
        let slurm = commands::batch::slurm::SlurmOptions {
            array_size: a.array_size,
            partition: a.partition,
            time: a.time,
            cpus: a.cpus.unwrap_or(1),
            submit: a.submit,
        };
        return commands::batch::slurm::slurm_command(&opts, &slurm, &rep, a.json);
    }
    commands::batch::batch_command(&opts, &rep, a.json)
}
