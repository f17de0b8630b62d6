//! The tester side: suites, bindings, runner, reports and the `harness` CLI.

pub mod cli;
pub mod outcome;
mod report;
mod model;
mod notation;
mod profile;
mod suite;
