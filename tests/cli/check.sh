# The command-line tests' checks, sourced after `work` (a scratch folder) is set.
fail=0; passed=0
check() {  # check "description" command...: counts a pass, or prints the failure
  local what="$1"; shift
  if "$@"; then passed=$((passed+1)); else echo "FAILED: $what"; fail=$((fail+1)); fi
}
expect_exit() {  # expect_exit CODE command...: stdout and stderr kept in $work/stdout, $work/stderr
  local want="$1"; shift
  "$@" >"$work/stdout" 2>"$work/stderr"; local got=$?
  if [ "$got" -ne "$want" ]; then echo "exit $got, expected $want: $*"; cat "$work/stderr"; return 1; fi
}
