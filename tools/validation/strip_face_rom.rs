//! A `[[strip]]` on a mesh face group beyond the dense limit of a matrix case (4000 free DOF),
//! solved on its Craig–Bampton model (`[reduction]`): the bar damper's bar (1.25 m × 10 mm ×
//! 10 mm, clamped at x = 0, pads on z = 0 and z = a, the face strip of `tests/strip_face_rom.rs`)
//! meshed with NX × NY × NZ hexahedra (`tests/support/face_bar.rs`), forced at the tip near its
//! first axial resonance at H = 1 with the exact cycle.
//!
//!     cargo run --release --example strip_face_rom -- NX NY NZ MODES [--full] [--modal=M1,M2,…]
//!
//! e.g. `-- 100 1 12 20` (7878 DOF). Prints the model and ROM sizes, the wall and CPU time of the
//! whole solve (model assembly, reduction and continuation; CPU time of the process over all its
//! threads, `/proc/self/stat`), the peak resident memory (`VmHWM`, `/proc/self/status`) and the
//! resonance peak of the tip's first harmonic. `--full` solves the unreduced case first (up to
//! 4000 free DOF) and prints the largest difference of the tip's harmonics at the map
//! frequencies relative to their amplitude. `--modal=M1,M2,…` solves the Craig–Bampton model
//! again on the modal coordinates of its M lowest modes (`[harmonic_balance] modes = M`) and
//! prints the same difference from the Craig–Bampton solution on its coordinates.
use std::f64::consts::TAU;
use std::time::Instant;

use nlrom::case::Case;
use nlrom::commands::progress::Reporter;
use nlrom::commands::solve::{solve_case, SolveOptions};
use nlrom::output::ResultsFile;
use nlrom::problem::rom_store::RomPolicy;

#[path = "../../tests/support/face_bar.rs"]
mod face_bar;
use face_bar::{agreement, case_text, response_difference, HexBar};

/// The map frequencies (Hz), where the reduced and the unreduced response are compared.
const MAP_HZ: [f64; 4] = [1300.0, 1330.0, 1345.0, 1360.0];

/// The case on `mesh`: the face strip of `tests/strip_face_rom.rs`, the exact cycle at H = 1
/// (on `modes` modal coordinates when given), maps at [`MAP_HZ`], then `reduction`.
fn bar_case(mesh: &std::path::Path, reduction: &str, modes: Option<usize>) -> String {
    let hz: Vec<String> = MAP_HZ.iter().map(|f| format!("{f:.1}")).collect();
    let strip = "face = \"pads\"\ndirection = [1.0, 0.0, 0.0]\nkt = 1.2e9\nmu = 0.3\npreload = 1000.0\nevaluation = \"analytic\"\nmap = 90\n";
    let tables = format!(
        "map_hz = [{}]\n\n[harmonic_balance]\nharmonics = 1\n{}\n[continuation]\nstart_hz = 1250.0\nend_hz = 1420.0\nstep_hz = 5.0\nmax_step_hz = 10.0\n{reduction}",
        hz.join(", "),
        modes.map_or(String::new(), |m| format!("modes = {m}\n"))
    );
    case_text(mesh, strip, &tables)
}

/// User + system CPU time (s) of this process over all its threads (`/proc/self/stat`).
fn process_cpu_s() -> f64 {
    let stat = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
    let rest = stat.rsplit_once(')').map_or("", |(_, r)| r);
    let f: Vec<&str> = rest.split_whitespace().collect();
    let tick = |i: usize| {
        f.get(i - 3)
            .and_then(|v| v.parse::<f64>().ok())
            .unwrap_or(0.0)
    };
    (tick(14) + tick(15)) / 100.0
}

/// Peak resident memory (MB) of the process so far (`VmHWM`).
fn peak_rss_mb() -> f64 {
    let status = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    status
        .lines()
        .find_map(|l| l.strip_prefix("VmHWM:"))
        .and_then(|v| v.trim().trim_end_matches("kB").trim().parse::<f64>().ok())
        .map_or(f64::NAN, |kb| kb / 1024.0)
}

fn solve(text: &str, dir: &std::path::Path) -> Result<ResultsFile, Box<dyn std::error::Error>> {
    let case = Case::from_str(text, &dir.join("bar.toml"))?;
    let (wall, cpu) = (Instant::now(), process_cpu_s());
    let out = solve_case(
        &case,
        &SolveOptions::new(RomPolicy::ReadIfMatching),
        &Reporter::silent(),
    )?;
    let frf = &out.results.frfs[0];
    let (mut peak, mut at) = (0.0f64, 0.0);
    for p in &frf.points {
        // the tip's first response DOF (x of its first node), harmonic 1
        let a = p.harmonics[1].norm();
        if a > peak {
            (peak, at) = (a, p.omega / TAU);
        }
    }
    println!(
        "  {} points, peak {peak:.4e} m at {at:.2} Hz; wall {:.1} s, CPU {:.1} s, peak RSS {:.0} MB",
        frf.points.len(),
        wall.elapsed().as_secs_f64(),
        process_cpu_s() - cpu,
        peak_rss_mb()
    );
    Ok(out.results)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let full = args.iter().any(|a| a == "--full");
    let modal: Vec<usize> = match args.iter().find_map(|a| a.strip_prefix("--modal=")) {
        Some(list) => list
            .split(',')
            .map(|m| m.trim().parse())
            .collect::<Result<_, _>>()?,
        None => Vec::new(),
    };
    let nums: Vec<usize> = args
        .iter()
        .filter(|a| !a.starts_with("--"))
        .map(|a| a.parse())
        .collect::<Result<_, _>>()?;
    let [nx, ny, nz, modes] = nums[..] else {
        return Err("usage: strip_face_rom NX NY NZ MODES [--full] [--modal=M1,M2,…]".into());
    };
    let bar = HexBar {
        length: 1.25,
        width: 0.01,
        height: 0.01,
        nx,
        ny,
        nz,
    };
    let dir = tempfile::tempdir()?;
    let mesh = dir.path().join("bar.msh");
    bar.write(&mesh)?;
    let pads = 2 * (nx + 1) * (ny + 1);
    println!(
        "bar {nx} × {ny} × {nz} hexahedra: {} nodes, {} DOF ({} clamped), {pads} pad nodes",
        bar.nodes(),
        3 * bar.nodes(),
        3 * (ny + 1) * (nz + 1)
    );
    let reference = if full {
        println!("unreduced:");
        Some(solve(&bar_case(&mesh, "", None), dir.path())?)
    } else {
        None
    };
    println!("Craig–Bampton, {modes} fixed-interface modes:");
    let reduction = format!("[reduction]\ninterface_modes = {modes}\n");
    let rom = solve(&bar_case(&mesh, &reduction, None), dir.path())?;
    for &m in &modal {
        println!("the same on its {m} lowest modes:");
        let on_modes = solve(&bar_case(&mesh, &reduction, Some(m)), dir.path())?;
        println!(
            "  on {m} modes − on the Craig–Bampton coordinates at the map frequencies: {:.2e} of the tip amplitude",
            response_difference(&on_modes, &rom)
        );
    }
    if let Some(reference) = reference {
        let agree = agreement(&rom, &reference, 1, 1e-4);
        println!(
            "reduced − unreduced at the map frequencies: {:.2e} of the tip amplitude, transition angles within {:.2e} rad",
            agree.harmonics, agree.angle
        );
    }
    Ok(())
}
