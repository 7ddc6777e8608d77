#!/usr/bin/env bash
# Run a command inside the rm_ros2 environment: scripts/with_env.sh <command> [args...]
set -eo pipefail
# shellcheck disable=SC1091
source "$(dirname "${BASH_SOURCE[0]}")/env.sh"
exec "$@"
