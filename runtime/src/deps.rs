//! Where `make setup` put the third-party parts (MuJoCo, robot packages): `.deps/` of the checkout,
//! compiled in from `.cargo/config.toml`, or `$AUTOBIO_DEPS` at run time.

use std::path::PathBuf;

pub fn deps_dir() -> PathBuf {
    if let Ok(p) = std::env::var("AUTOBIO_DEPS") {
        return PathBuf::from(p);
    }
    PathBuf::from(option_env!("AUTOBIO_DEPS").unwrap_or(".deps"))
}
