//! The march's steps allocate nothing once the step sizes and contact states of a period have been
//! met: a counting global allocator (this test binary's own) counts the heap allocations of the
//! marching thread in each of periods 2 to 5, for every scheme (zero, except in a period that
//! factors a step matrix met for the first time), on the underplatform damper
//! of Gastaldi & Berruti 2018 (cases/damper.toml, static start, three contacts with lift-off,
//! stick and slip) and on a one-DOF oscillator with a Jenkins element (stick–slip every half
//! period), soft and stiff (k_t = 400 N/m at ω = 0.2 rad/s: the adaptive standard step meets
//! corrector cycles and re-runs those steps with the full-stick step, without forming an error).

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::path::Path;

use nlrom::case::{Case, MarchScheme};
use nlrom::march::element::{Direction, Element};
use nlrom::march::law::FrictionParams;
use nlrom::march::signal::Harmonic;
use nlrom::march::{InitialCondition, MarchSettings, MarchSystem, Marcher};
use nlrom::problem::march_case::case_march;

/// Counts the allocations (and reallocations) of the threads that switched counting on.
struct Counting;

thread_local! {
    static COUNTING: Cell<bool> = const { Cell::new(false) };
    static COUNT: Cell<u64> = const { Cell::new(0) };
}

fn note() {
    // `try_with`: the thread-locals may be gone while a thread shuts down.
    let _ = COUNTING.try_with(|on| {
        if on.get() {
            let _ = COUNT.try_with(|c| c.set(c.get() + 1));
        }
    });
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        note();
        System.alloc(layout)
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        System.dealloc(ptr, layout)
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        note();
        System.alloc_zeroed(layout)
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        note();
        System.realloc(ptr, layout, new_size)
    }
}

#[global_allocator]
static ALLOCATOR: Counting = Counting;

/// Allocations of this thread while `f` runs.
fn allocations<T>(f: impl FnOnce() -> T) -> (T, u64) {
    COUNT.with(|c| c.set(0));
    COUNTING.with(|on| on.set(true));
    let out = f();
    COUNTING.with(|on| on.set(false));
    (out, COUNT.with(|c| c.get()))
}

/// m q̈ + c q̇ + k q + f_t = F cos ωt, Jenkins element (k_t = `kt` N/m, slip force μ n0) on q.
fn jenkins_oscillator(kt: f64) -> MarchSystem {
    let mut sys = MarchSystem {
        n: 1,
        mass: vec![1.0],
        damping: vec![0.02 * 2.0 * 3.0],
        stiffness: vec![4.0],
        force: vec![Harmonic::cosine(2.0, 0.0)],
        damping_force: Vec::new(),
        elements: vec![Element {
            name: "jenkins".into(),
            tangential: Direction {
                weights: vec![(0, 1.0)],
                prescribed: Harmonic::default(),
            },
            normal: None,
            params: FrictionParams {
                kt,
                kn: 0.0,
                mu: 1.0,
                n0: 0.5,
            },
            applies_normal: true,
        }],
        dof_names: vec!["q".into()],
        initial: InitialCondition::Rest,
        displacement_scale: 1.0,
    };
    sys.displacement_scale = sys.default_displacement_scale();
    sys
}

/// Marches one period, then periods 2..=5 counting the allocations and the new step-matrix
/// factorisations of each; returns them and the state changes of the last period (so the march
/// is known to cross contact-state transitions).
fn count_after_first_period(
    sys: &MarchSystem,
    settings: &MarchSettings,
) -> (Vec<(u64, usize)>, usize) {
    let mut m = Marcher::new(sys, settings).unwrap();
    m.march_period().unwrap();
    let per = (0..4)
        .map(|_| {
            let f0 = m.factorisations();
            let (_, count) = allocations(|| m.march_period().unwrap());
            (count, m.factorisations() - f0)
        })
        .collect();
    let out = m.finish();
    assert_eq!(out.periods.len(), 5);
    (per, out.periods.last().unwrap().state_changes)
}

#[test]
fn steps_allocate_nothing_after_the_first_period() {
    let case = Case::load(Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/cases/damper.toml"
    )))
    .unwrap();
    let jenkins = jenkins_oscillator(5.0);
    let stiff = jenkins_oscillator(400.0);
    let mut report: Vec<(bool, String)> = Vec::new();
    for scheme in MarchScheme::ALL.into_iter().filter(|s| !s.is_nonsmooth()) {
        let cm = case_march(&case, Some(scheme), &mut |_| {}).unwrap();
        let damper = MarchSettings {
            periods: 5,
            ..cm.settings.clone()
        };
        let oscillator = MarchSettings {
            scheme,
            omega: 2.0,
            periods: 5,
            steps_per_period: 200,
            ..MarchSettings::default()
        };
        let stiff_settings = MarchSettings {
            omega: 0.2,
            steps_per_period: 300,
            ..oscillator.clone()
        };
        for (name, sys, settings) in [
            ("damper", &cm.system, &damper),
            ("Jenkins oscillator", &jenkins, &oscillator),
            ("stiff Jenkins oscillator", &stiff, &stiff_settings),
        ] {
            let (per, changes) = count_after_first_period(sys, settings);
            assert!(
                changes >= 2,
                "{scheme} on the {name}: only {changes} state changes in the last period"
            );
            // a period allocates only to keep the factors of a (step, states) pair met for the
            // first time, and the last two periods meet none
            let ok = per.iter().all(|&(count, new)| count == 0 || new > 0)
                && per[2..].iter().all(|&(count, _)| count == 0);
            report.push((
                ok,
                format!(
                    "{scheme} on the {name}: (allocations, new factors) per period 2..=5 {per:?}"
                ),
            ));
        }
    }
    for (_, line) in &report {
        eprintln!("{line}");
    }
    let bad: Vec<&String> = report
        .iter()
        .filter(|(ok, _)| !ok)
        .map(|(_, l)| l)
        .collect();
    assert!(bad.is_empty(), "allocating steps: {bad:?}");
}
