# Two commands on a fresh machine: `make demo` and `make test`. Both run `make setup` first.
CARGO ?= cargo

.PHONY: setup build demo test hold-column bench baseline tasks-doc clean

setup:
	./scripts/setup.sh

build: setup
	$(CARGO) build --release

# The main job: check every shipped protocol, then the scripted expert on both thermal-cycler
# protocols, the close-then-open chain, the tube transfer, the mini centrifuge's lid, the 5430's
# lid opened with its key, the 5430's rotor balanced and the thermal mixer's panel (20 seeded
# episodes each), on the two-arm task and the Aloha tasks (tube pick-up with one arm; with two,
# the cap unscrewed, the cap screwed back on, and the vortex mixer's knob turned to a speed and
# the mixer switched on with the tube held in its cup) (5 each): a results table, results JSON and one MCAP recording per episode under
# out/demo/. Then a model server in the loop: the reference openpi server answering with those
# recordings, through `eval --suite suites/demo.toml --model`, its run packed as a leaderboard
# bundle, verified, and built into the site out/demo/site/index.html (scripts/demo-model.sh). Last, the no-motion control
# (`--policy hold`), which must score 0 everywhere.
demo: build
	rm -rf out/demo
	$(CARGO) run --release --quiet -- check protocols/*/*.toml
	$(CARGO) run --release --quiet -- eval \
	  --protocol protocols/thermal_cycler/close_lid.toml \
	  --protocol protocols/thermal_cycler/open_lid.toml \
	  --protocol protocols/thermal_cycler/close_then_open.toml \
	  --protocol protocols/tube/transfer.toml \
	  --protocol protocols/centrifuge_mini/close_lid.toml \
	  --protocol protocols/centrifuge_5430/open_lid.toml \
	  --protocol protocols/centrifuge/insert_symmetric.toml \
	  --protocol protocols/thermal_mixer/set_parameters.toml \
	  --episodes 20 --seed 0 --out out/demo --record
	$(CARGO) run --release --quiet -- eval \
	  --protocol protocols/two_arm/close_lid_and_transfer.toml \
	  --protocol protocols/tube/pick_up.toml \
	  --protocol protocols/tube/unscrew_cap.toml \
	  --protocol protocols/tube/screw_cap.toml \
	  --protocol protocols/tube/recap.toml \
	  --protocol protocols/vortex_mixer/mix_tube.toml \
	  --episodes 5 --seed 0 --out out/demo --record
	CARGO="$(CARGO)" ./scripts/demo-model.sh
	$(CARGO) run --release --quiet -- eval --policy hold \
	  --protocol protocols/thermal_cycler/close_lid.toml \
	  --protocol protocols/thermal_cycler/open_lid.toml \
	  --protocol protocols/tube/transfer.toml \
	  --protocol protocols/thermal_mixer/set_parameters.toml \
	  --protocol protocols/centrifuge_5430/open_lid.toml \
	  --protocol protocols/centrifuge/insert_symmetric.toml \
	  --protocol protocols/tube/pick_up.toml \
	  --protocol protocols/tube/unscrew_cap.toml \
	  --protocol protocols/tube/screw_cap.toml \
	  --protocol protocols/vortex_mixer/mix_tube.toml \
	  --episodes 3 --seed 0

test: setup
	$(CARGO) test --release --workspace --no-fail-fast
	# The Python package (python/tests) in its own environment, against the CLI just built, on
	# two workers (pytest-xdist).
	AUTOBIO_BIN=$${CARGO_TARGET_DIR:-target}/release/autobio \
	  .deps/python-env/bin/python -m pytest python/tests -q -p no:cacheprovider -n 2
	$(CARGO) clippy --release --workspace --all-targets -- -D warnings
	$(CARGO) fmt --all -- --check

# The task table's hold column re-measured on the table's own 100 seeds (3,200 episodes, about
# 40 minutes on 2 cores), or on its first HOLD_FIRST: every task must score 0 with no motion, and
# docs/tasks.md must list exactly the tasks that run; and its expert column on the first
# EXPERT_FIRST seeds: every task must win at least its row's Wilson lower bound of them. CI
# (.ci/run) runs both on a few seeds after `make test` on every commit, within its budget.
HOLD_FIRST ?= 100
EXPERT_FIRST ?= 10
hold-column: build
	$(CARGO) run --release --quiet -- tasks protocols --verify-hold docs/tasks.md --first $(HOLD_FIRST) --expert-first $(EXPERT_FIRST)

bench: build
	$(CARGO) run --release --quiet -- bench

# The learned baseline (docs/baseline.md): expert demonstrations of suites/baseline.toml's tasks,
# a state-based ACT trained on each with lerobot-train on the CPU, its learning curve on unseen
# seeds, the last checkpoints evaluated on the suite, packed, verified and built into
# out/baseline/site beside the paper's rows. Budget: STEPS (default 6000) per task; OBS=vision
# DEVICE=cuda for the same recipe with cameras on a GPU.
baseline: build
	CARGO="$(CARGO)" ./scripts/baseline.sh

# The task table: every shipped task under the expert and under hold on seeds 0-99
# (about 15 minutes on 2 cores).
tasks-doc: build
	$(CARGO) run --release --quiet -- tasks protocols --episodes 100 --seed 0 --workers 2 --out docs/tasks.md

clean:
	rm -rf out
