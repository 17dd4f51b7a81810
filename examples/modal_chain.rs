//! The harmonic balance on modal coordinates with the library API (`nlrom::hbm::modal`): a
//! linear structure given by its modes (as exported from a finite element code), a friction
//! element on one of its DOFs, the frequency response of the modal harmonics and the response
//! at a physical DOF.
//!
//!     cargo run --release --example modal_chain
//!
//! The structure is a fixed–free chain of n = 20 unit masses and springs k (first mode at 1
//! rad/s), whose mass-normalised modes are known in closed form:
//! φ_r(j) = 2/√(2n+1) sin((2r − 1)πj/(2n+1)), ω_r² = 4k sin²((2r − 1)π/(2(2n+1))); modal damping
//! ζ_r = 0.02. A Jenkins element (k_t = 5 N/m, slip force 0.2 N) holds the tip, which is forced
//! by 0.3 N cos ωt. The frequency response from 0.6 to 1.6 rad/s (H = 3) is traced with the
//! first m modes, m = 3, 6 and 20 (the full basis, whose solutions are those of the physical
//! coordinates, `tests/hbm_modal.rs`), and the tip's resonance printed for each.

use std::f64::consts::PI;

use faer::Mat;
use nlrom::case::WeightedDofs;
use nlrom::contact::grounded::{DofElement, DofElements};
use nlrom::contact::law::ContactParams;
use nlrom::continuation::ContinuationOptions;
use nlrom::harmonics::HarmonicLayout;
use nlrom::hbm::frf::frequency_response;
use nlrom::hbm::modal::ModalModel;
use nlrom::hbm::{HbmSystem, ResponseOptions};

fn main() -> nlrom::Result<()> {
    let n = 20;
    let h = 3;
    let tip = n - 1;
    let odd = |r: usize| (2 * r + 1) as f64;
    let spring = (1.0 / (2.0 * (PI / (2 * (2 * n + 1)) as f64).sin())).powi(2);
    let shape = |j: usize, r: usize| {
        2.0 / ((2 * n + 1) as f64).sqrt()
            * (odd(r) * PI * (j + 1) as f64 / (2 * n + 1) as f64).sin()
    };
    let omega = |r: usize| 2.0 * spring.sqrt() * (odd(r) * PI / (2 * (2 * n + 1)) as f64).sin();
    for modes in [3, 6, 20] {
        // the modal model: ω_r, ζ_r and the shapes at the contact, forced and response DOFs
        // (all three the tip here), one row per DOF and one column per mode
        let tip_shapes = || Mat::from_fn(1, modes, |_, r| shape(tip, r));
        let model = ModalModel::new(
            (0..modes).map(omega).collect(),
            vec![0.02; modes],
            tip_shapes(),
            tip_shapes(),
            vec![0.3],
            tip_shapes(),
        )?;
        // the friction element on the contact DOF 0 (the first row of the contact shapes)
        let jenkins = DofElements::new(
            vec![DofElement {
                tangential: WeightedDofs {
                    dofs: vec![0],
                    weights: vec![1.0],
                },
                normal: None,
                params: ContactParams::new(5.0, 0.0, 1.0, 0.2, "jenkins")?,
            }],
            1,
        )?;
        let linear = model.linear_model(h)?;
        let force = model.project(jenkins)?;
        let system = HbmSystem::new(HarmonicLayout::new(h, 64)?, &linear, &force)?;
        // the modal Jacobian is dense: every solver choice takes the dense LU
        let options = ContinuationOptions::new(0.6, 1.6, 0.02);
        let response = ResponseOptions::default();
        let frf = frequency_response(&system, &options, &response, &mut |_| {})?;
        let mut peak = (0.0, 0.0);
        for p in &frf.points {
            let tip_response = model.physical_response(&p.response, &response)?;
            if tip_response.amplitude[0] > peak.1 {
                peak = (p.omega, tip_response.amplitude[0]);
            }
        }
        println!(
            "{modes:2} modes ({} unknowns): {} points ({:?}), tip resonance {:.6} m at {:.6} rad/s",
            system.dim(),
            frf.points.len(),
            frf.end,
            peak.1,
            peak.0
        );
    }
    Ok(())
}
