#!/usr/bin/env bash
# The chaos label: hostile cases against the guarantees of README.md
# ("What catchup guarantees") and docs/run-output.md, each checked by what a
# user sees: the exit status, the one stderr line, and the bytes of every
# file before and after (an input, an earlier good result). The full-disk
# cases, which need a small tmpfs, are in disk.sh.
#   chaos.sh CATCHUP-RUN CATCHUP-SWEEP MPIEXEC SOURCE-DIR WORK-DIR [CASE...]
rm -rf "$5"
. "$(dirname "$0")/common.sh"

# ---- "It destroys files": an input is never an output ----------------------
case_input_output() {
  mkdir -p io/sub && cp "$EX/paper-fig2.yaml" io/s.yaml && cp -r "$EX/sparse-mtx" io/mtx &&
    cp "$EX/circuits/clamp.cir" io/c.cir && cp "$EX/sweep-smoke.yaml" io/sw.yaml &&
    cp "$EX/paper-fig2.yaml" "$EX/paper-fig3.yaml" io/ || return
  ln -sf s.yaml io/link.h5
  ln -f io/s.yaml io/hard.h5
  printf 'netlist: c.cir\n' > io/n.yaml
  printf 'rc\nV1 in 0 SIN(0 5 50)\n.include parts.inc\n.tran 20u 20m\n.end\n' > io/i.cir
  printf 'R1 in out 1k\nC1 out 0 1u\nD1 0 out\n' > io/parts.inc
  keep io/s.yaml io/mtx/* io/c.cir io/sw.yaml io/n.yaml io/i.cir io/parts.inc
  expect 1 "the output io/s.yaml is io/s.yaml, which the run reads" "$RUN" io/s.yaml -o io/s.yaml &&
  expect 1 "is io/s.yaml, which the run reads (the same path)" "$RUN" io/s.yaml -o io/link.h5 &&
  expect 1 "is io/s.yaml, which the run reads (the same file)" "$RUN" io/s.yaml -o io/hard.h5 &&
  expect 1 "which the run reads" "$RUN" io/s.yaml -o io/sub/../s.yaml &&
  expect 1 "the output io/mtx/C.mtx is io/mtx/C.mtx" "$RUN" io/mtx/scene.yaml -o io/mtx/C.mtx &&
  expect 1 "the output io/c.cir is io/c.cir" "$RUN" io/c.cir -o io/c.cir &&
  expect 1 "the output io/c.cir is io/c.cir" "$RUN" io/n.yaml -o io/c.cir &&
  expect 1 "the output io/parts.inc is io/parts.inc" "$RUN" io/i.cir -o io/parts.inc &&
  expect 1 "the output io/sw.yaml is io/sw.yaml" "$SWEEP" io/sw.yaml -o io/sw.yaml &&
  expect 1 "the output io/paper-fig3.yaml is io/paper-fig3.yaml" "$SWEEP" io/sw.yaml -o io/paper-fig3.yaml &&
  expect 1 "which the run reads" "$SWEEP" io/sw.yaml -o io/sw.yaml --resume &&
  kept io/s.yaml io/mtx/C.mtx io/c.cir io/sw.yaml io/parts.inc &&
    ok "-o naming an input (path, symlink, hard link, netlist, .include, .mtx, sweep file, a sweep's scene) is refused; every input intact"
}

# ---- "It destroys files": a failed run never destroys an earlier result -----
case_earlier_result() {
  mkdir -p er && "$RUN" "$EX/circuits/clamp.cir" -o er/k.h5 --quiet || { fail "the first run failed"; return; }
  cp "$EX/sweep-smoke.yaml" "$EX/paper-fig2.yaml" "$EX/paper-fig3.yaml" er/ &&
    "$SWEEP" er/sweep-smoke.yaml -o er/sw.h5 --quiet || { fail "the first sweep failed"; return; }
  keep er/k.h5 er/sw.h5
  expect 1 "no node named 'nowhere'" "$RUN" "$EX/circuits/clamp.cir" -o er/k.h5 --probe 'v(nowhere)' &&
  expect 1 "--probe: the scene has no netlist" "$RUN" "$EX/paper-fig2.yaml" -o er/k.h5 --probe 'v(a)' &&
  expect 1 "circuit.R1" "$RUN" "$EX/paper-fig2.yaml" -o er/k.h5 --set circuit.R1=-1 &&
  expect 1 "needs D = 0" "$RUN" "$EX/circuits/halfwave-rc.cir" -o er/k.h5 --scheme explicit --n 100 &&
  expect 1 "cannot open" "$RUN" er/missing.yaml -o er/k.h5 &&
  expect 1 "variants" "$SWEEP" /dev/null -o er/sw.h5 &&
  kept er/k.h5 er/sw.h5 && ok "a run or a sweep that fails its checks leaves the earlier result byte for byte"
}

# ---- a read-only output folder ------------------------------------------------
case_readonly() {
  mkdir -p ro && "$RUN" "$EX/paper-fig2.yaml" -o ro/k.h5 --quiet || { fail "the first run failed"; return; }
  keep ro/k.h5
  if [ "$(id -u)" -ne 0 ]; then
    chmod 555 ro
    expect 1 "cannot create a file beside it" "$RUN" "$EX/paper-fig2.yaml" -o ro/k.h5
    chmod 755 ro
  elif unshare --mount true 2> /dev/null; then      # root ignores modes: a read-only bind mount
    unshare --mount bash -c "mount --bind ro ro && mount -o remount,bind,ro ro && \
      '$RUN' '$EX/paper-fig2.yaml' -o ro/k.h5 > out.txt 2> err.txt; echo \$? > rc.txt"
    [ "$(cat rc.txt)" = 1 ] && [ "$(grep -c '' err.txt)" = 1 ] && grep -q "Read-only file system" err.txt ||
      { fail "read-only folder: exit $(cat rc.txt): $(cat err.txt)"; return; }
  else
    echo "skip [$case]: root, and no mount namespace for a read-only folder"; return
  fi
  kept ro/k.h5 && ok "a read-only output folder: one line, the earlier file intact"
}

# ---- "--resume mixes inputs" -----------------------------------------------
case_resume_inputs() {
  mkdir -p ri && cp "$EX/circuits/halfwave-rc.cir" "$EX/circuits/halfwave-rc.yaml" ri/ &&
    sed 's/n: \[600, 1500, 3000\]/n: [600, 1500]/' "$EX/circuits/rectifier-sweep.yaml" > ri/sweep.yaml || return
  # stopped after its first jobs (SIGTERM from the task callback's poll is
  # timing-dependent; a finished file is refused the same way)
  "$SWEEP" ri/sweep.yaml -o ri/r.h5 --quiet || { fail "the sweep failed"; return; }
  keep ri/r.h5
  sed -i 's/C1 out 0 100u/C1 out 0 10u/' ri/halfwave-rc.cir
  expect 1 "ri/halfwave-rc.cir changed since the file was made" "$SWEEP" ri/sweep.yaml -o ri/r.h5 --resume &&
  kept ri/r.h5 || return
  # what a netlist includes, and a Matrix Market file, are hashed too
  printf 'rc\nV1 in 0 SIN(0 5 50)\n.include parts.inc\n.tran 20u 20m\n.end\n' > ri/i.cir
  printf 'R1 in out 1k\nC1 out 0 1u\nD1 0 out\n' > ri/parts.inc
  printf 'name: inc\nbase: i.cir.yaml\ngrid: {n: [100]}\nvariants:\n  - name: a\n' > ri/inc.yaml
  printf 'netlist: i.cir\n' > ri/i.cir.yaml
  cp -r "$EX/sparse-mtx" ri/mtx && printf 'base: mtx/scene.yaml\ngrid: {n: [100]}\nvariants:\n  - name: a\n' > ri/mtx.yaml
  "$SWEEP" ri/inc.yaml -o ri/i.h5 --quiet && "$SWEEP" ri/mtx.yaml -o ri/m.h5 --quiet || { fail "the sweeps failed"; return; }
  keep ri/i.h5 ri/m.h5
  sed -i 's/1u/2u/' ri/parts.inc && sed -i '$ s/0/1/' ri/mtx/x0.mtx
  expect 1 "ri/parts.inc changed since the file was made" "$SWEEP" ri/inc.yaml -o ri/i.h5 --resume &&
  expect 1 "ri/mtx/x0.mtx changed since the file was made" "$SWEEP" ri/mtx.yaml -o ri/m.h5 --resume &&
  kept ri/i.h5 ri/m.h5 && ok "--resume after a netlist, an included file or a .mtx was edited is refused, naming it; the results files intact"
}

# ---- "Messages are cut" ----------------------------------------------------
case_deep_path() {
  local d=deep
  while [ ${#d} -lt 250 ]; do d=$d/$(printf 'p%.0s' $(seq 1 50)); done
  mkdir -p "$d" && sed 's/L3: 2/L3: -2/' "$EX/paper-fig2.yaml" > "$d/s.yaml" || return
  expect 1 "$d/s.yaml:" "$RUN" "$d/s.yaml" -o "$d/o.h5" &&
  grep -qE "circuit.L3: must be > 0 \(got -2\)$" err.txt || { fail "cut: $(cat err.txt)"; return; }
  printf 'base: s.yaml\ngrid: {n: [10]}\nvariants:\n  - name: a\n    set: {circuit.L3: -3}\n' > "$d/sw.yaml"
  expect 1 "$d/sw.yaml:4:5: variants.0 (a)" "$SWEEP" "$d/sw.yaml" -o "$d/o.h5" &&
  grep -qE "circuit.L3: must be > 0 \(got -3\)$" err.txt || { fail "cut: $(cat err.txt)"; return; }
  ok "through a ${#d}-character folder, catchup-run's and catchup-sweep's messages end whole"
}

# ---- "No bound" -------------------------------------------------------------
# Refused at once: before the first step, so that no step is taken at all.
# Every refused command runs with a tripwire that a run past its checks
# trips before its first step, and the run then ends otherwise than the
# refusal (not exit 1 with its one line): catchup-run's
# CATCHUP_RUN_TEST_SIGNAL=1, SIGINT at the first sample (the state at t = 0,
# exit 130); catchup-sweep's CATCHUP_SWEEP_DONE_LIST naming its two tasks,
# an abort when one is computed (its reference is the adaptive scheme's,
# not 8e9 fixed steps before the tasks). A bound in steps, exact (0 against
# the 1e9 to 1e18 asked), not in seconds: a 5 s wall-clock limit failed
# under load (the refusals take ~0.04 s each).
case_no_bound() {
  mkdir -p nb && printf 'a clamp asking for 10^18 steps\nV1 in 0 SIN(0 5 50)\nR1 in out 1k\nC1 out 0 1u\nD1 out 0\n.tran 1f 1k\n.end\n' > nb/huge.cir &&
    "$RUN" "$EX/paper-fig2.yaml" -o nb/k.h5 --quiet || { fail "the first run failed"; return; }
  keep nb/k.h5
  printf '0\n1\n' > nb/tasks.txt
  local trip=(env CATCHUP_RUN_TEST_SIGNAL=1 CATCHUP_SWEEP_DONE_LIST=nb/tasks.txt)
  expect 1 "the output needs about 5.498e+11 MiB" "${trip[@]}" "$RUN" nb/huge.cir -o nb/k.h5 &&
  expect 1 "n = 1e+12 steps (--h) exceed the limit of 1000000000 (--max-steps, the scene key max_steps): take fewer steps, or the adaptive scheme with an error target (--scheme adaptive --tol 1e-6), and store fewer samples (output.samples)" \
    "${trip[@]}" "$RUN" nb/huge.cir -o nb/k.h5 --h 1e-9 &&
  expect 1 "n = 100 steps (the scene's n) exceed the limit of 50" "${trip[@]}" "$RUN" "$EX/paper-fig2.yaml" -o nb/k.h5 --max-steps 50 &&
  expect 1 "n = 100 steps (the scene's n) exceed the limit of 50" "${trip[@]}" "$RUN" "$EX/paper-fig2.yaml" -o nb/k.h5 --set max_steps=50 &&
  expect 1 "n = 2e+09 steps (--n) exceed the limit" "${trip[@]}" "$RUN" "$EX/paper-fig2.yaml" -o nb/k.h5 --n 2e9 &&
  printf 'base: %s\ngrid: {n: [100, 2000000000]}\nvariants:\n  - name: a\nreference: {method: adaptive}\n' "$EX/paper-fig2.yaml" > nb/sw.yaml &&
  expect 1 "n = 2e+09 steps (task 1, variant a: grid.n) exceed the limit" "${trip[@]}" "$SWEEP" nb/sw.yaml -o nb/k.h5 &&
  kept nb/k.h5 || return
  [ ! -e nb/huge.h5 ] && ok "absurd step counts refused before a step, naming .tran / n and the alternatives; the earlier file intact"
}

# ---- "Interrupts lose the state" --------------------------------------------
# same A B: /t, /x, /signals and /events of two files equal, value for value
# and in shape (h5diff exits 0 for datasets of different shapes, "not
# comparable": a resumed run with a row lost or doubled would pass it)
shapes() { h5ls -r "$1" | grep -E '^/(t|x|signals/.*|events) '; }
same() { [ "$(shapes "$1")" = "$(shapes "$2")" ] && h5diff -q "$1" "$2" /t /t && h5diff -q "$1" "$2" /x /x && { ! h5ls "$1/signals" > /dev/null 2>&1 || h5diff -q "$1" "$2" /signals /signals; } && { [ "$(h5ls "$1/events" | grep -o '{[0-9]*')" = "{0" ] || h5diff -q "$1" "$2" /events /events; }; }

case_interrupts() {
  mkdir -p it
  local args=("$EX/paper-fig2.yaml" --n 300000 --set output=final --quiet)
  "$RUN" "${args[@]}" -o it/whole.h5 || { fail "the whole run failed"; return; }
  # a final-output run stopped by SIGINT keeps the state, flagged; SIGTERM too
  CATCHUP_RUN_TEST_SIGNAL=0 "$RUN" "${args[@]}" -o it/final.h5 2> err.txt
  local rc=$?
  [ $rc = 130 ] && grep -q "stopped by SIGINT at step 1024 .*it/final.h5 holds the samples before it and, as its last row (stop_row), the state there: continue with --resume" err.txt ||
    { fail "SIGINT: exit $rc: $(cat err.txt)"; return; }
  [ "$(attr it/final.h5 stop_row)" = 0 ] && [ "$(attr it/final.h5 samples)" = 1 ] && [ "$(attr it/final.h5 status)" = -14 ] &&
    [ "$(h5dump -d t it/final.h5 | sed -n 's/^ *(0): //p' | head -1)" = "0.00341333" ] || { fail "the stop's row: $(h5dump -d t it/final.h5)"; return; }
  local k
  for k in 1 2 3; do CATCHUP_RUN_TEST_SIGNAL=0 "$RUN" "${args[@]}" -o it/final.h5 --resume 2> /dev/null; done
  "$RUN" "${args[@]}" -o it/final.h5 --resume || { fail "the last resume failed"; return; }
  same it/whole.h5 it/final.h5 || { fail "final output: the resumed run differs"; return; }
  [ -z "$(attr it/final.h5 stop_row)" ] && ! h5ls it/final.h5/checkpoint > /dev/null 2>&1 || { fail "flag or checkpoint left"; return; }
  # a netlist's signals, theta (the exact LCP step), stopped at samples by SIGTERM-like hooks and a real signal
  "$RUN" "$EX/circuits/halfwave-rc.cir" -o it/w.h5 --quiet || { fail "the netlist run failed"; return; }
  CATCHUP_RUN_TEST_SIGNAL=700 "$RUN" "$EX/circuits/halfwave-rc.cir" -o it/r.h5 --quiet 2> /dev/null
  for k in 1 2; do CATCHUP_RUN_TEST_SIGNAL=1000 "$RUN" "$EX/circuits/halfwave-rc.cir" -o it/r.h5 --quiet --resume 2> /dev/null; done
  "$RUN" "$EX/circuits/halfwave-rc.cir" -o it/r.h5 --quiet --resume && same it/w.h5 it/r.h5 || { fail "netlist: differs"; return; }
  # the adaptive scheme's samples inside a step reach the file in batches (integrator_set_put): stopped inside
  # one (the 100th sample: 99 rows, then the flagged state), inside the next ones, then to the end
  local pr=("$EX/circuits/precision-rectifier.cir" --tol 1e-6 --set output.samples=3001 --quiet)
  "$RUN" "${pr[@]}" -o it/pw.h5 || { fail "the adaptive netlist run failed"; return; }
  CATCHUP_RUN_TEST_SIGNAL=100 "$RUN" "${pr[@]}" -o it/pr.h5 2> /dev/null
  [ "$(attr it/pr.h5 stop_row)" = 99 ] || { fail "adaptive netlist: stop_row $(attr it/pr.h5 stop_row), not 99"; return; }
  for k in 1 2; do CATCHUP_RUN_TEST_SIGNAL=1000 "$RUN" "${pr[@]}" -o it/pr.h5 --resume 2> /dev/null; done
  "$RUN" "${pr[@]}" -o it/pr.h5 --resume && same it/pw.h5 it/pr.h5 || { fail "adaptive netlist: differs"; return; }
  ok "SIGINT keeps the state as a flagged last row (output: final too); --resume, stopped again and again, ends bit for bit as a run never stopped (a netlist's signals too, theta and adaptive)"
}

# Signals at whatever step they land, SIGINT and SIGTERM, for the explicit
# scheme's projector path, theta and the adaptive scheme.
case_signals() {
  mkdir -p sg
  local sc=0 args name
  for name in activeset theta adaptive; do
    case $name in
      activeset) args=("$EX/paper-fig2.yaml" --n 6000000 --projector activeset --set output.every=100 --quiet) ;;
      theta) args=("$EX/paper-fig3.yaml" --n 3000000 --eps 1e-12 --scheme theta --set output.every=100 --quiet) ;;
      adaptive) args=("$EX/paper-fig2.yaml" --scheme adaptive --tol 1e-10 --set T=5000 --set max_event_rate=1000 --set output.every=3 --quiet) ;;
    esac
    "$RUN" "${args[@]}" -o "sg/$name-whole.h5" || { fail "$name: the whole run failed"; return; }
    # --foreground: one signal to catchup-run alone. Without it timeout also
    # signals its own process group, catchup-run a second time, and a second
    # signal ends a run at once (by design, README), at times before it
    # saved its checkpoint: the next --resume then rightly finds none.
    local sig=INT stops=0 rc=130 tries=0
    rm -f "sg/$name.h5"
    timeout --foreground --preserve-status -s INT 0.2 "$RUN" "${args[@]}" -o "sg/$name.h5" 2> "sg/$name.err"; rc=$?
    while [ $rc -ne 0 ] && [ $tries -lt 40 ]; do
      [ $rc = 130 ] || [ $rc = 143 ] || { fail "$name: exit $rc after $stops signals: $(tail -n 2 "sg/$name.err") (the run before it: $(tail -n 2 "sg/$name.err0" 2> /dev/null))"; return; }
      stops=$((stops + 1)) tries=$((tries + 1))
      sig=$([ $sig = INT ] && echo TERM || echo INT)
      mv "sg/$name.err" "sg/$name.err0"   # the stopped run's message, named with the resume's on a failure
      # A signal before the handlers are set (a loaded machine can take that
      # long to start) ends the process by default, before any file: start again.
      local resume=--resume; [ -e "sg/$name.h5" ] || resume=
      timeout --foreground --preserve-status -s $sig 0.$((RANDOM % 3 + 1)) "$RUN" "${args[@]}" -o "sg/$name.h5" $resume 2> "sg/$name.err"; rc=$?
    done
    same "sg/$name-whole.h5" "sg/$name.h5" || { fail "$name: resumed after $stops signals, differs"; return; }
    sc=$((sc + stops))
  done
  ok "$sc SIGINT/SIGTERM at random steps, each run resumed: the projector path, theta and adaptive end bit for bit"
}

# --resume continues only the same run.
case_resume_refusals() {
  mkdir -p rr && cp -r "$EX/sparse-mtx" rr/m && cp "$EX/circuits/halfwave-rc.cir" rr/ || return
  CATCHUP_RUN_TEST_SIGNAL=10 "$RUN" rr/m/scene.yaml -o rr/m.h5 2> /dev/null
  CATCHUP_RUN_TEST_SIGNAL=10 "$RUN" rr/halfwave-rc.cir -o rr/c.h5 2> /dev/null
  keep rr/m.h5 rr/c.h5
  expect 1 "rr/m.h5: cannot resume: it ran another scene" "$RUN" rr/m/scene.yaml -o rr/m.h5 --resume --n 999 &&
  expect 1 "it records other signals than this run" "$RUN" rr/halfwave-rc.cir -o rr/c.h5 --resume --probe 'v(out)' &&
  sed -i '$ s/0$/1/' rr/m/x0.mtx &&
  expect 1 "rr/m.h5: cannot resume: rr/m/x0.mtx changed since the file was made" "$RUN" rr/m/scene.yaml -o rr/m.h5 --resume &&
  sed -i 's/C1 out 0 100u/C1 out 0 10u/' rr/halfwave-rc.cir &&
  expect 1 "rr/c.h5: cannot resume: rr/halfwave-rc.cir changed since the file was made" "$RUN" rr/halfwave-rc.cir -o rr/c.h5 --resume &&
  expect 1 "cannot continue 'rr/none.h5': no such file" "$RUN" rr/halfwave-rc.cir -o rr/none.h5 --resume &&
  kept rr/m.h5 rr/c.h5 || return
  "$RUN" "$EX/paper-fig2.yaml" -o rr/done.h5 --quiet &&
  expect 1 "rr/done.h5: cannot resume: it has no checkpoint" "$RUN" "$EX/paper-fig2.yaml" -o rr/done.h5 --resume &&
  CATCHUP_RUN_TEST_SIGNAL=10 expect 130 "this run cannot be resumed: a circuit with switches has no checkpoints; run it again" \
    "$RUN" "$EX/circuits/buck-ccm.cir" -o rr/sw.h5 &&
  expect 1 "rr/sw.h5: cannot resume: it has no checkpoint: a run of this kind keeps none" "$RUN" "$EX/circuits/buck-ccm.cir" -o rr/sw.h5 --resume &&
  "$RUN" "$EX/crowd-corridor.yaml" --set n=20 --set T=1 -o rr/cr.h5 --quiet && keep rr/cr.h5 &&
  expect 1 "rr/cr.h5: cannot resume: it has no checkpoint: a run of this kind keeps none (a crowd" \
    "$RUN" "$EX/crowd-corridor.yaml" --set n=20 --set T=1 -o rr/cr.h5 --resume && kept rr/cr.h5 &&
  ok "--resume refuses another scene, other overrides or signals, an edited .mtx or netlist, a finished file, a switched run and a crowd's (no checkpoints, said at the stop and at the resume); the files intact"
}

# kill -9 between rows: the file opens as it is, with the rows of its last
# flush; one killed during a resume resumes again to the same end.
case_kill9() {
  mkdir -p k9
  local args=("$EX/paper-fig2.yaml" --n 20000000 --set output.every=10 --quiet)
  "$RUN" "${args[@]}" -o k9/whole.h5 || { fail "the whole run failed"; return; }
  "$RUN" "$EX/paper-fig2.yaml" --n 1000000000 --set output.every=100 --quiet -o k9/k.h5 & local pid=$!
  # kill it once its first rows are flushed (polled: on a loaded machine a
  # fixed sleep can land before the first flush)
  local w=0 rows
  while [ $w -lt 300 ] && ! HDF5_USE_FILE_LOCKING=FALSE h5ls k9/k.h5/t 2> /dev/null | grep -q '{[1-9]'; do sleep 0.1; w=$((w + 1)); done
  sleep 0.2; kill -9 $pid 2> /dev/null; wait $pid 2> /dev/null
  rows=$(h5ls k9/k.h5/t | grep -o '{[0-9]*' | tr -d '{')
  [ "$(attr k9/k.h5 status_name)" = '"running"' ] && [ "${rows:-0}" -gt 0 ] && h5dump -d x k9/k.h5 > /dev/null ||
    { fail "kill -9: status $(attr k9/k.h5 status_name), ${rows:-no} rows"; return; }
  CATCHUP_RUN_TEST_SIGNAL=30000 "$RUN" "${args[@]}" -o k9/r.h5 2> /dev/null
  "$RUN" "${args[@]}" -o k9/r.h5 --resume & pid=$!
  sleep 0.15; kill -9 $pid 2> /dev/null; wait $pid 2> /dev/null
  "$RUN" "${args[@]}" -o k9/r.h5 --resume && same k9/whole.h5 k9/r.h5 ||
    { fail "a resume killed by kill -9, resumed again, differs"; return; }
  ok "kill -9 between rows leaves a readable file ($rows rows, status running); a killed resume resumes to the same end"
}

run_cases input_output earlier_result readonly resume_inputs deep_path no_bound interrupts signals resume_refusals kill9
