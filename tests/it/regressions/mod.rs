//! One test per fixed bug, each on the (shrunk) scene that showed it. A file is named for what
//! went wrong; its module doc names the issue, the cause and the fix.

mod ball_struck_on_the_floor;
mod balls_sliding_together;
mod bed_energy_below_zero;
mod check_bad_scene_exit_status;
mod closed_pipe;
mod driven_sweep_energy_left;
mod ensemble_without_tolerances;
mod fast_ball_into_wall;
mod floor_starting_from_rest;
mod forced_ball_through_wall;
mod forced_floor_acceleration;
mod free_chain_balance_roundoff;
mod horizon_row_missing;
mod impacts_out_of_order;
mod issue_14_touching_chain;
mod json_prints_every_impact;
mod loaded_contact_sinks;
mod overdamped_bed_balance;
mod plugin_driven_by_app_update;
mod pressed_at_the_horizon;
mod record_beyond_double_range;
mod record_point_inside_step;
mod resting_ball_without_energy;
mod row_pressed_into_wall;
mod series_beyond_memory;
mod spatial_series_read_back;
pub(crate) mod squeezed_ball_stops;
mod stale_impulse_bounce;
mod stiff_frame_rapier_step;
mod stopped_run_prints_nothing;
mod summary_without_bare_floors;
mod touching_balls_refused;
mod valid_input_panics;
mod walls_across_unnamed;
mod zero_speed_impact_at_start;
mod zero_time_event_loop;
