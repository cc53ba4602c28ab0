//! Leaderboard: will turn submitted results (the `scoring` results JSON, schema version 1) into
//! reports. Nothing is implemented yet: this crate holds the place in the workspace layout so the
//! one-way data flow (dsl -> compiler -> runtime -> scoring -> leaderboard) is fixed from the start.
