#!/usr/bin/env bash
# Guest instructions per HIL lock-step step, by what they do: runs the line juggler for
# 1 000 steps with QEMU in one-instruction-per-block mode, logging every executed guest
# instruction (`-singlestep -d exec,nochain`), then counts them by the function they are in.
# The wait for the next frame (the server's loop, the link's reads) is in "the rest" here;
# scripts/hil-guest-count.sh leaves it out.
# Exact (not timed), so it can be run on a loaded machine. Needs ~1 GB in $TMPDIR for the log.
# Usage: scripts/hil-guest-profile.sh [FIRMWARE_ELF]
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release -q -p dexter-sim
cargo build -q -p dexter-mps2-an386 --release --target thumbv7em-none-eabihf
elf=${1:-target/thumbv7em-none-eabihf/release/dexter-mps2-an386}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
qemu=$(command -v qemu-system-arm)
cat > "$work/qemu-system-arm" <<WRAP
#!/bin/sh
exec "$qemu" -singlestep -d exec,nochain -D "$work/exec.log" "\$@"
WRAP
chmod +x "$work/qemu-system-arm"
steps=1000 # --duration 2 at the scene's 500 Hz
PATH="$work:$PATH" target/release/dexter run scenes/line-juggler.toml --hil --duration 2 \
  --json --firmware "$elf" > /dev/null
awk -v steps="$steps" '{ s = $NF; c = "the rest (the wait for the frame, semihosting calls, start-up, Configure, Stop)"
  if (s ~ /^(memcpy|memset|__aeabi_mem)|memcpy|memclr|memset/) c = "memcpy/memset (copies of frames and commands)"
  else if (s ~ /unstuff|7receive17h|5Inbox|decode_from|FrameDecoder|cobs3dec|8postcard2de|SeqAccess|Flavor.*pop/) c = "decode (COBS, postcard, the inbox)"
  else if (s ~ /crc/) c = "CRC-32C (both directions)"
  else if (s ~ /finish_frame|13DeviceMessage6encode|4send|8postcard3ser|serialize_field|cobs3enc/) c = "encode (postcard, COBS)"
  else if (s ~ /FixedRate\$GT\$4step/) c = "control step"
  else if (s ~ /server/) c = "server glue (run, step, output, handle, check_kind)"
  n[c]++; total++ }
  END { for (c in n) printf "%8.0f  %s\n", n[c] / steps, c; printf "%8.0f  total per step\n", total / steps }' \
  "$work/exec.log" | sort -rn
