# The steps of the test scripts: each long step says what it does and how long it takes, and
# when it is done, how long it took. Sourced, not run (bash):
#
#   . scripts/step.sh
#   step "cargo test" "the first time about 15 min on 2 cores"   # ends the step before
#   ...
#   step_end                                                     # ends the last step
#
# The expected durations are measured on a 2-core machine (docs/setup-costs.md); a step's own
# line says what it took, and step_end lists every step of the script with its time.

_step_name=""
_step_start=0
_step_log=()

_step_minutes() { printf '%d min %02d s' "$(($1 / 60))" "$(($1 % 60))"; }

# step NAME [EXPECTED]: ends the running step, then announces NAME (and the time it should take).
step() {
    _step_finish
    _step_name="$1"
    _step_start=$SECONDS
    echo "== [$(date +%H:%M:%S)] $1${2:+ — $2}"
}

_step_finish() {
    if [ -n "$_step_name" ]; then
        local took=$((SECONDS - _step_start))
        echo "   ($_step_name: $(_step_minutes "$took"))"
        _step_log+=("$(_step_minutes "$took")  $_step_name")
        _step_name=""
    fi
}

# step_end: ends the running step and lists the time of each step.
step_end() {
    _step_finish
    local line
    echo "== $(basename "$0"): $(_step_minutes "$SECONDS") in all"
    for line in "${_step_log[@]}"; do echo "   $line"; done
}
