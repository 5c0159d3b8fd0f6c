# SPDX-License-Identifier: MIT
# Stage timing for tools/test.sh (sourced, under set -e): `stage NAME COMMAND [ARGS...]` runs
# COMMAND as a named stage and records how long it took. When the script exits, whether every
# stage passed or one failed, the table of stage times is printed (a failed stage is marked
# FAILED with its exit code) and the script's exit code is kept, so a failure still fails CI.
stage_times=""
stage_name=""
stage_start=$SECONDS

stage() {
  stage_name=$1
  shift
  stage_start=$SECONDS
  "$@"
  stage_times+=$(printf '%-28s %4d s' "$stage_name" $((SECONDS - stage_start)))$'\n'
  stage_name=""
}

print_stage_times() {
  local rc=$?
  if [ -n "$stage_name" ]; then
    stage_times+=$(printf '%-28s %4d s  FAILED (exit %d)' "$stage_name" $((SECONDS - stage_start)) "$rc")$'\n'
  fi
  printf '\nTime per stage:\n%s' "$stage_times"
  exit "$rc"
}
trap print_stage_times EXIT
