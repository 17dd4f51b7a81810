//! The robustness corpus, fast subset: generated friction cases (chains of Jenkins elements,
//! tangential–normal pairs that separate; H from 1 to 15, N_t from 2H + 2 up to 256, excitation
//! from 0.01 to 100 × the slip force, damping 0.1–5 %) traced over 0.2–2.5 rad/s. Every accepted
//! point must satisfy the Newton tolerance (1e-8, scaled); the number of curves that reach their
//! end must not fall below the measured count.

mod corpus;

const TOLERANCE: f64 = 1e-8;

/// The first 32 cases of the corpus. The goal is that every curve reaches its end; today 26 of
/// these 32 do (measured; `docs/validation.md` lists the classes that still stop: N_t close to
/// 2H + 2, tangential–normal pairs that separate at low frequency, gross slip with tiny steps).
/// The test keeps that floor and checks every accepted point against the tolerance.
#[test]
fn generated_curves_reach_their_end_within_the_tolerance() {
    const CASES: u64 = 32;
    const REACHED_AT_LEAST: usize = 26;
    let mut reached = 0;
    let mut stopped = vec![];
    for i in 0..CASES {
        let case = corpus::case(i, 256);
        let outcome = corpus::run(&case);
        assert!(
            outcome.points == 0 || outcome.worst_residual <= TOLERANCE,
            "{}: an accepted point has the residual {:.2e}",
            case.label,
            outcome.worst_residual
        );
        if outcome.reached_end {
            reached += 1;
        } else {
            stopped.push(format!("{}: {}", case.label, outcome.end));
        }
    }
    println!(
        "{reached} of {CASES} curves reached their end; stopped:\n{}",
        stopped.join("\n")
    );
    assert!(
        reached >= REACHED_AT_LEAST,
        "{reached} of {CASES} curves reached their end (at least {REACHED_AT_LEAST} did before):\n{}",
        stopped.join("\n")
    );
}
