#!/usr/bin/env bash
# The chaos label's full-disk cases, on a 16 MiB tmpfs mounted in a mount
# namespace of this script's own (unshare --mount, as .ci/run does): a run
# that cannot fit is refused with the numbers; a run that grows beyond its
# plan stops with the margin kept and a valid file; a full disk never
# destroys an earlier result. Skipped (exit 77) where the namespace or the
# mount is not allowed.
#   disk.sh CATCHUP-RUN CATCHUP-SWEEP MPIEXEC SOURCE-DIR WORK-DIR [CASE...]
if [ "${CHAOS_DISK_INSIDE:-}" != 1 ]; then
  rm -rf "$5"
  mkdir -p "$5/disk"
  if ! unshare --mount sh -c "mount -t tmpfs -o size=1m tmpfs '$5/disk'" 2> /dev/null; then
    echo "skip: no mount namespace with a tmpfs here (unshare --mount, mount -t tmpfs: not root, or not allowed)"
    exit 77
  fi
  CHAOS_DISK_INSIDE=1 exec unshare --mount bash "$0" "$@"
fi
. "$(dirname "$0")/common.sh"
DISK=$WORK/disk
MIB=1048576

# fresh DIR: a new 16 MiB tmpfs on $DISK
fresh() { umount "$DISK" 2> /dev/null; mount -t tmpfs -o size=16m tmpfs "$DISK"; }
free_bytes() { df -B1 --output=avail "$DISK" | tail -1; }

case_no_room() {
  fresh
  expect 1 "the output needs about 305.2 MiB and 8 MiB kept free beside it, and the device of $DISK/a.h5 has 16 MiB free" \
    "$RUN" "$EX/paper-fig2.yaml" -o "$DISK/a.h5" --n 10000000 &&
  [ -z "$(ls "$DISK")" ] && ok "a run that cannot fit the free disk is refused with the numbers; nothing written"
}

# The adaptive scheme storing each of its steps has no size known in
# advance: the writer checks as the file grows, counting what HDF5 still
# caches (34 signals: up to 37 MiB, more than the disk).
case_grows() {
  fresh
  cp "$EX/paper-fig2.yaml" "$DISK/" && "$RUN" "$EX/paper-fig2.yaml" -o "$DISK/k.h5" --quiet || { fail "the first run failed"; return; }
  keep "$DISK/k.h5" "$DISK/paper-fig2.yaml"
  local sc
  for sc in paper ladder; do
    if [ $sc = paper ]; then
      expect 1 "h5run: stopped writing '$DISK/$sc.h5' after" "$RUN" "$EX/paper-fig2.yaml" -o "$DISK/$sc.h5" \
        --scheme adaptive --tol 1e-10 --set T=20000 --set output.every=1 || return
    else
      expect 1 "h5run: stopped writing '$DISK/$sc.h5' after" "$RUN" "$EX/circuits/ladder.cir" -o "$DISK/$sc.h5" \
        --scheme adaptive --probe all --set T=200 --set output.every=1 || return
    fi
    grep -q "rows: less than 8 MiB left on its device" err.txt || { fail "$(cat err.txt)"; return; }
    local free status rows
    free=$(free_bytes) status=$(attr "$DISK/$sc.h5" status) rows=$(attr "$DISK/$sc.h5" samples)
    [ "$status" = -10 ] && [ "$rows" -gt 0 ] && h5dump -d t "$DISK/$sc.h5" > /dev/null ||
      { fail "$sc: status '$status', $rows samples, or the file is not readable"; return; }
    [ "$free" -ge $((7 * MIB)) ] || { fail "$sc: $free bytes left: the 8 MiB margin was not kept"; return; }
    rm -f "$DISK/$sc.h5"
  done
  kept "$DISK/k.h5" && ok "runs that outgrow their plan stop with a readable file (status CUP_ERR_IO), >= 7 MiB left"
}

# A full disk, and a run asked to replace an earlier result there.
case_full() {
  fresh
  "$RUN" "$EX/paper-fig2.yaml" -o "$DISK/k.h5" --quiet || { fail "the first run failed"; return; }
  keep "$DISK/k.h5"
  local avail
  avail=$(free_bytes)
  head -c $((avail - 4 * MIB)) /dev/zero > "$DISK/filler"
  expect 1 "and 8 MiB kept free beside it, and the device of $DISK/k.h5 has 4 MiB free" "$RUN" "$EX/paper-fig2.yaml" -o "$DISK/k.h5" --n 10 &&
  expect 1 "its device has" "$SWEEP" "$EX/sweep-smoke.yaml" -o "$DISK/k.h5" &&
  kept "$DISK/k.h5" && ok "on a full disk a run and a sweep are refused; the earlier result is intact"
}

run_cases no_room grows full
