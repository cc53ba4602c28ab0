//! The leaderboard: evaluation results (`results::run::EvalReport`, results schema
//! [`results::run::RESULTS_SCHEMA_VERSION`]) turned into reports and submissions. The results tables
//! `autobio eval` and `autobio results merge` print ([`table`]); submission bundles packed from
//! suite runs and unpacked from strangers' files under limits ([`bundle`]); and their offline
//! verification ([`verify`]), which re-enacts every episode from its seed and actions through a
//! simulator the caller hands in; the online audit's statistics ([`audit`]); and the static site
//! built from a folder of bundles ([`site`]). The shipped suites and protocols are compiled in
//! ([`shipped`]): verification needs no checkout.
//!
//! It links no simulator: it reads what runs wrote, through `results`, and runs nothing itself.
//!
//! Its tests are beside the code and in the workspace's tests/leaderboard.rs and
//! tests/site_browser.rs.

pub mod audit;
pub mod bundle;
pub mod shipped;
pub mod site;
pub mod table;
pub mod verify;
