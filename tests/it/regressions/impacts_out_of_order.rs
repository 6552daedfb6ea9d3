//! The contact model's one-line path stamped an impact at its step's start plus the gap over the
//! approach speed. A row of touching balls (large, small, large) carried into the right wall
//! showed it: the last ball's wall impact was stamped where its gap closed, late in the step,
//! and the knock-on it caused between the balls at the step's start, up to 1.4 ms earlier with
//! fixed steps of 2 ms. `impacts.csv` then listed an impact before the one that caused it. An
//! impact is now never stamped before those booked before it, and a slow approach's stamp
//! stays within its step: the list is in time order.

use lpc_damper::model::{Model, RunOptions};
use lpc_damper::scene::Stepping;

use crate::common::{damper, PAPER_FRAME};

#[test]
fn impacts_of_a_touching_row_are_listed_in_time_order() {
    for stepping in [Stepping::Aligned, Stepping::Fixed] {
        let mut scene = damper(PAPER_FRAME, 0.0185, &[0.11, 0.011, 0.11], 0.9, 0.0, 0.01, 2.0);
        scene.rapier.stepping = Some(stepping);
        for model in [Model::Rapier, Model::Reference, Model::Compliant] {
            let run = model.simulate(&scene, &RunOptions::default()).unwrap();
            assert!(run.impacts.len() > 10, "{model} with {stepping:?} steps");
            if let Some(k) = (1..run.impacts.len()).find(|&k| run.impacts[k].t < run.impacts[k - 1].t) {
                panic!(
                    "{model} with {stepping:?} steps: impact {k} at {} s is listed after one at {} s",
                    run.impacts[k].t,
                    run.impacts[k - 1].t
                );
            }
        }
    }
}
