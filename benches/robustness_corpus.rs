//! The full robustness corpus of the harmonic balance continuation: 320 generated friction cases
//! (`tests/corpus`: chains of 1–6 masses with Jenkins elements, tangential–normal pairs that
//! separate; H ∈ {1, 3, 5, 7, 15}, N_t from 2H + 2 to 4096, excitation 0.01–100 × the slip
//! force, damping 0.1–5 %, steps 0.005–0.08 rad/s). Prints one line per case (with its jumps and
//! the longest stretch of frequency a jump left untraced) and the success rate, points, Newton
//! iterations and time per curve.
//!
//! `cargo bench --bench robustness_corpus` (add `-- N` for the first N cases, `-- only=3,17,188`
//! for chosen cases, `-- analytic` to evaluate every friction element by the exact
//! continuous-time cycle instead of the AFT).

#[path = "../tests/corpus/mod.rs"]
mod corpus;

/// The case numbers to run: `only=a,b,…` when given, else the first N (a plain number; 320).
fn case_numbers() -> Vec<u64> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if let Some(list) = args.iter().find_map(|a| a.strip_prefix("only=")) {
        return list
            .split(',')
            .filter_map(|c| c.trim().parse().ok())
            .collect();
    }
    let count: u64 = args.iter().find_map(|a| a.parse().ok()).unwrap_or(320);
    (0..count).collect()
}

fn main() {
    let numbers = case_numbers();
    let count = numbers.len() as u64;
    let evaluation = if std::env::args().any(|a| a == "analytic") {
        corpus::Evaluation::Analytic
    } else {
        corpus::Evaluation::Aft
    };
    let (mut reached, mut points, mut iterations, mut seconds) = (0, 0, 0, 0.0);
    let mut jumped = 0;
    let mut worst: f64 = 0.0;
    for i in numbers {
        let case = corpus::evaluated(corpus::case(i, 4096), evaluation);
        let o = corpus::run(&case);
        println!(
            "{:<100} {:>5} pts {:>6} its {:>8.3} s  worst residual {:.1e}  jumps {} (largest gap {:.3} rad/s)  {}",
            case.label,
            o.points,
            o.iterations,
            o.seconds,
            o.worst_residual,
            o.jumps,
            o.largest_gap,
            if o.reached_end { "end" } else { &o.end }
        );
        reached += usize::from(o.reached_end);
        jumped += usize::from(o.reached_end && o.jumps > 0);
        points += o.points;
        iterations += o.iterations;
        seconds += o.seconds;
        worst = worst.max(o.worst_residual);
    }
    let n = count as f64;
    println!(
        "{reached} of {count} curves reached their end ({:.1} %; {jumped} of them with a jump of the sweep); per curve: {:.1} points, {:.1} Newton iterations, {:.3} s; worst accepted residual {worst:.2e}",
        100.0 * reached as f64 / n,
        points as f64 / n,
        iterations as f64 / n,
        seconds / n
    );
}
