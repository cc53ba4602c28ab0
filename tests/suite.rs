//! The workspace's integration tests, in one test binary: each file under tests/ is a module
//! here (one link of the workspace instead of one per file; see docs/decisions.md, "One test
//! binary"). They run the real MuJoCo, real files, the real `autobio` binary and real servers on
//! loopback. A new test file is a new `mod` line below.
// Tests print the figures they measure (shown with --nocapture).
#![allow(clippy::print_stdout)]

mod common;

mod aloha;
mod architecture;
mod authoring;
mod build_loop;
mod centrifuge_mini;
mod centrifuges;
mod chains;
mod cli;
mod contact_and_position;
mod datasets;
mod deploy;
mod episode_failures;
mod expert_episodes;
mod faulty_corpus;
mod forgeries;
mod golden;
mod hold_control;
mod import;
mod import_autoprotocol;
mod instruments_act;
mod inversion;
mod kinematics;
mod lab_runs;
mod labware_models;
mod leaderboard;
mod learned_policy;
mod level_of_detail;
mod liquid_scene;
mod liquids_and_definitions;
mod merge;
mod model_faults;
mod model_servers;
mod no_simulator;
mod observation_history;
mod paper_fidelity;
mod pcr_setup;
mod perturb;
mod photoreal;
mod pictures;
mod pipette;
mod planning;
mod processes;
mod protocol_diagnostics;
mod reach;
mod replay;
mod resume;
mod scale;
mod scene_files;
mod settle;
mod shipped_suites;
mod site_browser;
mod step_by_hand;
mod synth;
mod thermal_mixer;
mod tube_transfer;
mod two_arms;
mod vortex_mixing;
mod workflows;
mod wrong_outcomes;
