#!/usr/bin/env bash
# One idempotent set-up step for rm_ros2 on a machine without ROS:
#   1. create .venv (python3.11, or $PYTHON),
#   2. install the pinned ROS 2 Jazzy wheels and libraries from requirements/lock.txt,
#   3. make the venv an ament underlay (scripts/make_venv_underlay.py),
#   4. colcon build the workspace into build/ and install/ (with vendor/'s interface
#      packages that the wheels lack),
#   5. compile the control loop's modules with mypyc (scripts/build_compiled.py).
# Each step is skipped when its inputs have not changed since it last succeeded, so a
# second run with nothing changed takes a few seconds. Source scripts/env.sh afterwards.
set -euo pipefail

ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
VENV="$ROOT/.venv"
STAMPS="$VENV/.rm_ros2"
PYTHON=${PYTHON:-python3.11}
export ROS_AUTOMATIC_DISCOVERY_RANGE=${ROS_AUTOMATIC_DISCOVERY_RANGE:-LOCALHOST}

log() { printf '[setup] %s\n' "$*"; }
digest() { sha256sum "$@" | sha256sum | cut -c1-16; }

if ! command -v "$PYTHON" >/dev/null 2>&1; then
  if python3 -c 'import sys; sys.exit(sys.version_info[:2] != (3, 11))' 2>/dev/null; then
    PYTHON=python3
  else
    echo "[setup] error: the ROS 2 Jazzy wheels need CPython 3.11; set PYTHON=/path/to/python3.11" >&2
    exit 1
  fi
fi

# 1. virtualenv
if [ ! -x "$VENV/bin/python" ]; then
  log "creating $VENV with $PYTHON"
  "$PYTHON" -m venv "$VENV"
fi
mkdir -p "$STAMPS"

# 2. pinned packages, 3. venv as ament underlay
lock_digest=$(digest "$ROOT/requirements/lock.txt" "$ROOT/scripts/make_venv_underlay.py")
if [ "$(cat "$STAMPS/lock" 2>/dev/null)" != "$lock_digest" ]; then
  log "installing requirements/lock.txt (about a minute on a cold cache)"
  "$VENV/bin/python" -m pip install --quiet --disable-pip-version-check \
    -r "$ROOT/requirements/lock.txt" 2> >(grep -v "^WARNING: Location" >&2)
  "$VENV/bin/python" "$ROOT/scripts/make_venv_underlay.py"
  echo "$lock_digest" > "$STAMPS/lock"
  rm -f "$STAMPS/build"
fi

# 4. colcon build. With --symlink-install the Python sources are used in place, so a
# rebuild is needed only when manifests, messages, data files or the venv change.
cd "$ROOT"
# Interface packages the wheels lack (vendor/, e.g. tf2_msgs): built where Python cannot
# import them; a ROS install has the real ones.
vendor_paths=()
for vendor_pkg in vendor/*/; do
  vendor_pkg=${vendor_pkg%/}
  if ! "$VENV/bin/python" -c "import $(basename "$vendor_pkg").msg" 2>/dev/null; then
    vendor_paths+=("$vendor_pkg")
  fi
done
build_inputs=$(find rm_msgs rm_base rm_plugins rm_bringup vendor \
  \( -name '__pycache__' -o -name '*.egg-info' \) -prune -o \
  \( -path 'rm_msgs/*' -o -path 'vendor/*' -o -name setup.py -o -name setup.cfg -o -name package.xml \
     -o -name plugins.xml -o -path '*/resource/*' -o -path 'rm_bringup/config/*' \
     -o -path 'rm_bringup/launch/*' \) -type f -print | LC_ALL=C sort)
build_digest=$( (echo "$lock_digest"; echo "$build_inputs"; cat $build_inputs) | sha256sum | cut -c1-16)
if [ "$(cat "$STAMPS/build" 2>/dev/null)" != "$build_digest" ] || [ ! -f install/setup.bash ]; then
  log "colcon build (output in log/setup-build.log)"
  mkdir -p "$ROOT/log"
  (
    set +u  # the activate and setup scripts are not nounset-safe
    # shellcheck disable=SC1091
    source "$VENV/bin/activate"
    source "$VENV/local_setup.bash"
    colcon --log-base log build --symlink-install \
      --base-paths "${vendor_paths[@]}" rm_msgs rm_base rm_plugins rm_bringup \
      --cmake-args -DBUILD_TESTING=OFF
  ) > "$ROOT/log/setup-build.log" 2>&1 || {
    tail -n 40 "$ROOT/log/setup-build.log" >&2
    echo "[setup] colcon build failed; full output in log/setup-build.log" >&2
    exit 1
  }
  echo "$build_digest" > "$STAMPS/build"
fi
# 5. the control loop's modules compiled with mypyc beside their sources (rm_base/runtime/compiled.py
# names them); rebuilt when one of them changed. Without it they run from source, slower.
mkdir -p "$ROOT/log"
"$VENV/bin/python" "$ROOT/scripts/build_compiled.py" --if-changed > "$ROOT/log/build-compiled.log" 2>&1 || {
  tail -n 40 "$ROOT/log/build-compiled.log" >&2
  echo "[setup] compiling the loop failed; full output in log/build-compiled.log" >&2
  exit 1
}
log "ready: source scripts/env.sh"
