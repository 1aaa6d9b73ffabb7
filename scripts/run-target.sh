#!/usr/bin/env bash
# The runner of every thumbv7em-none-eabihf binary cargo runs from the workspace root
# (.cargo/config.toml), chosen by the image:
#   dexter-mps2-an386           -> QEMU mps2-an386 (the QEMU image; `cargo fw`)
#   dexter-nucleo-f446re        -> probe-rs: flash the NUCLEO-F446RE and print its defmt log
#   the same with `qemu-hsi`    -> QEMU netduinoplus2, USART2 (the host link) on a
#                                  pseudo-terminal it names (`cargo board-emu`)
# defmt's binary frames never reach a terminal: on a terminal the QEMU image's log goes
# through `defmt-print` (cargo install defmt-print), or, without it, into a file this
# script names. Usage: scripts/run-target.sh ELF [ARGS...] (cargo passes the ELF).
set -euo pipefail
elf=$1
shift
name=$(basename "$elf")
need() { command -v "$1" >/dev/null || { echo "error: $1 not found: $2" >&2; exit 1; }; }

case "$name" in
  dexter-nucleo-f446re*)
    if grep -q DEXTER_QEMU_HSI_IMAGE "$elf"; then
      need qemu-system-arm "install it (Debian: apt-get install qemu-system-arm)"
      echo "NUCLEO-F446RE image (qemu-hsi) in QEMU netduinoplus2; the line below names USART2's port:" >&2
      echo "  dexter run scenes/line-juggler.toml --hil --port /dev/pts/N    (Ctrl-C stops QEMU)" >&2
      exec qemu-system-arm -machine netduinoplus2 -nographic -monitor none \
        -serial null -serial pty -kernel "$elf" "$@"
    fi
    need probe-rs "install it with 'cargo install probe-rs-tools' (or run the emulated board: cargo board-emu)"
    exec probe-rs run --chip STM32F446RETx "$elf" "$@"
    ;;
  *)
    need qemu-system-arm "install it (Debian: apt-get install qemu-system-arm)"
    qemu=(qemu-system-arm -machine mps2-an386 -nographic -monitor none -serial null
          -icount shift=10 -semihosting-config enable=on,target=native -kernel "$elf" "$@")
    if [ ! -t 1 ]; then
      exec "${qemu[@]}"
    fi
    if command -v defmt-print >/dev/null; then
      "${qemu[@]}" | defmt-print -e "$elf"
      exit "${PIPESTATUS[0]}"
    fi
    log="$elf.defmt"
    status=0
    "${qemu[@]}" >"$log" || status=$?
    echo "the firmware's log is binary defmt, written to $log; read it with" >&2
    echo "  defmt-print -e $elf < $log     (cargo install defmt-print)" >&2
    exit "$status"
    ;;
esac
