#!/usr/bin/env bash
# One setup step: runs an installer and, when it fails, says which step failed and the command
# to run by hand, instead of leaving a bare exit status. Sourced by the ensure-*.sh scripts.
#   setup_step <step name> <command to run by hand> <installer command...>
setup_step() {
    local step="$1" by_hand="$2"
    shift 2
    if ! "$@"; then
        echo "error: setup step '$step' failed ($* exited non-zero); run it by hand: $by_hand" >&2
        return 1
    fi
}
