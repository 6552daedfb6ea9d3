//! `lpc stress --extreme` drew line scenes of 640 and 6259 balls whose contact-model steps take
//! a quarter to half a second each: with `--max-wall-time 0.5` one run went on for 44 s to its
//! horizon and another for 120 s, because the models looked at the clock only every 256 steps.
//! A meter now also looks on the steps 1, 2, 4, ... before its first regular look, so a run of
//! slow steps overruns its budget by at most the time it had taken when it last looked.

use lpc_damper::model::{Budget, Limits, Meter, RunOptions};

#[test]
fn the_wall_time_budget_is_looked_at_from_the_first_step() {
    let options = RunOptions::limited(Limits { max_wall_s: Some(1e-3), ..Limits::NONE });
    let meter = Meter::new(&options, 256);
    // The first step took longer than the whole budget.
    std::thread::sleep(std::time::Duration::from_millis(5));
    assert_eq!(meter.look(0.1, 1), Some(Budget::WallTime));
    assert_eq!(meter.look(0.1, 2), Some(Budget::WallTime));
    // Between the early looks and the regular ones, none.
    assert_eq!(meter.look(0.1, 3), None);
    assert_eq!(meter.look(0.1, 255), None);
    assert_eq!(meter.look(0.1, 256), Some(Budget::WallTime));
}
