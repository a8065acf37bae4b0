# Shared by the CLI tests (tests/cli/test_*.sh; this folder is not globbed as a test).
# Sets T (a temporary folder removed at exit) and fails; defines:
#   pass NAME / fail NAME            record a result (fail counts)
#   expect CODE NAME CMD...          run CMD, check its exit status; stdout in $T/out, stderr in $T/err
#   err_has TEXT                     $T/err mentions TEXT (grep -q)
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
fails=0
pass() { echo "ok   $1"; }
fail() { echo "FAIL $1"; fails=$((fails + 1)); }
expect() {
  local want=$1 name=$2; shift 2
  "$@" >"$T/out" 2>"$T/err"; local got=$?
  if [ "$got" = "$want" ]; then pass "$name (exit $got)"; else fail "$name: exit $got, wanted $want"; sed 's/^/     /' "$T/err" | head -5; fi
}
err_has() { if grep -q -- "$1" "$T/err"; then pass "  message mentions '$1'"; else fail "  message lacks '$1':"; sed 's/^/     /' "$T/err" | head -5; fi; }
