//! The real board's image (`boards/nucleo-f446re`): it builds for the target, its sizes
//! match `boards/nucleo-f446re/expected/sizes.txt` (a change in size shows up in review)
//! and stay within its budgets, and the documents quote the expected file. Regenerate on
//! purpose with `DEXTER_BLESS=1 cargo test -p dexter-tests --test board`.
//!
//! The image itself cannot run here (QEMU's netduinoplus2 hangs in its HSE clock setup, see
//! firmware/README.md, "Emulation"); the same image on the internal oscillator (feature
//! `qemu-hsi`) runs in the loop under emulation in `host-sim/tests/board_hil.rs`.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::process::Command;

const TARGET: &str = "thumbv7em-none-eabihf";
const CRATE: &str = "dexter-nucleo-f446re";
/// Flash budget: the image fits the smallest STM32F4 with this pinout (64 KiB parts exist
/// in the family; the F446RE has 512 KiB), so growth is seen long before it matters.
const FLASH_BUDGET: u64 = 64 * 1024;
/// RAM budget for statics plus the whole reserved stack.
const RAM_BUDGET: u64 = 16 * 1024;

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn board_dir() -> PathBuf {
    root().join("boards/nucleo-f446re")
}

/// The image's feature sets all link to one path: one build (and copy) at a time.
static BUILD: std::sync::Mutex<()> = std::sync::Mutex::new(());

/// `cargo ARGS` from the workspace root, which must succeed (`what` names it on failure).
fn cargo(args: &[&str], what: &str) {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let out = Command::new(cargo)
        .current_dir(root())
        .args(args)
        .output()
        .expect("run cargo");
    assert!(
        out.status.success(),
        "{what} (cargo {}) failed:\n{}",
        args.join(" "),
        String::from_utf8_lossy(&out.stderr)
    );
}

/// Build the board image (release) and return a copy of its ELF
/// (`dexter-nucleo-f446re-product.elf`, which another feature set's build does not replace).
fn board_elf() -> PathBuf {
    let _one_at_a_time = BUILD.lock().unwrap_or_else(|e| e.into_inner());
    cargo(
        &["build", "-p", CRATE, "--release", "--target", TARGET],
        "building the board image",
    );
    let target = std::env::var_os("CARGO_TARGET_DIR")
        .map(|d| root().join(d))
        .unwrap_or_else(|| root().join("target"));
    let release = target.join(TARGET).join("release");
    let copy = release.join(format!("{CRATE}-product.elf"));
    std::fs::copy(release.join(CRATE), &copy).expect("copy the board image");
    copy
}

/// Section sizes the way `size` (Berkeley) counts them, and the reserved stack.
struct Sizes {
    text: u64,
    data: u64,
    bss: u64,
    stack_reserved: u64,
}

fn u16_at(b: &[u8], o: usize) -> usize {
    u16::from_le_bytes([b[o], b[o + 1]]) as usize
}

fn u32_at(b: &[u8], o: usize) -> u64 {
    u64::from(u32::from_le_bytes(b[o..o + 4].try_into().unwrap()))
}

/// (type, flags, offset, size, link) of every section header of an ELF32 LE file.
fn sections(b: &[u8]) -> Vec<(u64, u64, usize, usize, usize)> {
    assert_eq!(&b[..5], b"\x7fELF\x01", "ELF32 expected");
    let shoff = u32_at(b, 0x20) as usize;
    let (entsize, count) = (u16_at(b, 0x2e), u16_at(b, 0x30));
    (0..count)
        .map(|i| {
            let h = shoff + i * entsize;
            let (off, size) = (u32_at(b, h + 16) as usize, u32_at(b, h + 20) as usize);
            (
                u32_at(b, h + 4),
                u32_at(b, h + 8),
                off,
                size,
                u32_at(b, h + 24) as usize,
            )
        })
        .collect()
}

/// The `len` bytes the image holds at address `addr` (in a section with file contents).
fn bytes_at(b: &[u8], addr: u64, len: usize) -> Option<&[u8]> {
    let shoff = u32_at(b, 0x20) as usize;
    let (entsize, count) = (u16_at(b, 0x2e), u16_at(b, 0x30));
    (0..count).find_map(|i| {
        let h = shoff + i * entsize;
        let (ty, start) = (u32_at(b, h + 4), u32_at(b, h + 12));
        let (off, size) = (u32_at(b, h + 16) as usize, u32_at(b, h + 20));
        const NOBITS: u64 = 8;
        let inside =
            ty != NOBITS && start != 0 && addr >= start && addr + len as u64 <= start + size;
        inside.then(|| &b[off + (addr - start) as usize..][..len])
    })
}

/// The size of symbol `name` (its `st_size`).
fn symbol_size(b: &[u8], name: &str) -> Option<u64> {
    let all = sections(b);
    let &(_, _, off, size, link) = all.iter().find(|s| s.0 == 2)?;
    let strtab = all[link].2;
    (off..off + size).step_by(16).find_map(|sym| {
        let at = strtab + u32_at(b, sym) as usize;
        let end = b[at..].iter().position(|&c| c == 0)?;
        (&b[at..at + end] == name.as_bytes()).then(|| u32_at(b, sym + 8))
    })
}

fn symbol(b: &[u8], name: &str) -> Option<u64> {
    let all = sections(b);
    let &(_, _, off, size, link) = all.iter().find(|s| s.0 == 2)?; // SHT_SYMTAB
    let strtab = all[link].2;
    (off..off + size).step_by(16).find_map(|sym| {
        let at = strtab + u32_at(b, sym) as usize;
        let end = b[at..].iter().position(|&c| c == 0)?;
        (&b[at..at + end] == name.as_bytes()).then(|| u32_at(b, sym + 4))
    })
}

fn sizes(elf: &Path) -> Sizes {
    let b = std::fs::read(elf).unwrap();
    let (mut text, mut data, mut bss) = (0, 0, 0);
    const WRITE: u64 = 1;
    const ALLOC: u64 = 2;
    const NOBITS: u64 = 8;
    for (ty, flags, _, size, _) in sections(&b) {
        let size = size as u64;
        match (flags & ALLOC != 0, ty == NOBITS, flags & WRITE != 0) {
            (false, _, _) => {}
            (true, true, _) => bss += size,
            (true, false, true) => data += size,
            (true, false, false) => text += size,
        }
    }
    let top = symbol(&b, "_stack_start").expect("_stack_start");
    let bottom = symbol(&b, "_stack_end").expect("_stack_end");
    Sizes {
        text,
        data,
        bss,
        stack_reserved: top - bottom,
    }
}

fn sizes_text(s: &Sizes) -> String {
    format!(
        "# {CRATE} release ELF ({TARGET}), bytes; flash = text + data, static RAM = data + bss,\n\
         # stack = the region memory.x reserves\n\
         text {}\ndata {}\nbss {}\nflash {}\nstatic_ram {}\nstack_reserved {}\n",
        s.text,
        s.data,
        s.bss,
        s.text + s.data,
        s.data + s.bss,
        s.stack_reserved
    )
}

fn bless() -> bool {
    std::env::var_os("DEXTER_BLESS").is_some_and(|v| !v.is_empty() && v != "0")
}

fn number(text: &str, key: &str) -> u64 {
    text.lines()
        .find_map(|l| l.strip_prefix(key)?.strip_prefix(' ')?.parse().ok())
        .unwrap_or_else(|| panic!("no `{key} N` line in\n{text}"))
}

/// The table firmware/README.md and BENCHMARKS.md quote, from the expected file.
fn size_table(sizes: &str) -> String {
    let get = |key| number(sizes, key);
    let kib = |b: u64| format!("{:.1} KiB", b as f64 / 1024.0);
    let (flash, ram, stack) = (get("flash"), get("static_ram"), get("stack_reserved"));
    format!(
        "<!-- generated from boards/nucleo-f446re/expected/sizes.txt by tests/board.rs \
         (DEXTER_BLESS=1 regenerates); do not edit -->\n\
         | figure (NUCLEO-F446RE image) | value | goal |\n| --- | --- | --- |\n\
         | flash (text {} + data {}) | {flash} B = {} | <= 64 KiB (of the part's 512 KiB) |\n\
         | static RAM (data + bss, RTT buffer and RTIC task state included) | {ram} B | |\n\
         | stack reserved (memory.x) | {stack} B | high-water: reported by the board (defmt, `Stopped`) |\n\
         | RAM: statics + reserved stack | {} B = {} | <= 16 KiB (of the part's 128 KiB) |\n",
        get("text"),
        get("data"),
        kib(flash),
        ram + stack,
        kib(ram + stack),
    )
}

fn check_block(doc: &Path, block: &str) {
    let text = std::fs::read_to_string(doc).unwrap();
    let marker = "<!-- generated from boards/nucleo-f446re/expected/";
    let start = text
        .find(marker)
        .unwrap_or_else(|| panic!("{}: no generated board size table", doc.display()));
    let end = text[start..]
        .find("\n\n")
        .map_or(text.len(), |e| start + e + 1);
    if bless() {
        std::fs::write(doc, format!("{}{block}{}", &text[..start], &text[end..])).unwrap();
        return;
    }
    assert_eq!(
        &text[start..end],
        block,
        "{} quotes other board figures than {} (DEXTER_BLESS=1 regenerates)",
        doc.display(),
        board_dir().join("expected/sizes.txt").display()
    );
}

/// The `Configure` frame a HIL host sends for `scenes/line-juggler.toml`: the scene
/// validated and turned into the core's parameters by the simulator, encoded by the core's
/// protocol (`LockStep::start` sends exactly `HostMessage::Configure(C::config(params))`).
fn host_configure() -> Vec<u8> {
    use dexter_core::control::Controller;
    use dexter_core::fixed_rate::FixedRate;
    use dexter_core::protocol::{encode, HostMessage, Wire, MAX_FRAME_LEN};
    let scene = dexter_tests::load_scene("line-juggler", &[]);
    let params = scene.controller_params().expect("a sil scene");
    <Controller as FixedRate>::new(params).expect("the core accepts the scene's tuning");
    let mut buf = [0u8; MAX_FRAME_LEN];
    let n = encode(
        &HostMessage::Configure(Controller::config(params)),
        &mut buf,
    )
    .unwrap();
    buf[..n].to_vec()
}

/// The stand-alone loop runs the scene's controller, bit for bit: the `Configure` frame
/// linked into the board image (symbol `DEXTER_SCENE_CONFIGURE`, which `scene_params`
/// decodes at reset) and the checked-in `scene.configure` it is built from are the
/// host's frame for the line juggler's scene. (`dexter board scenes/line-juggler.toml
/// --write boards/nucleo-f446re/scene.configure` regenerates the file.)
fn assert_the_board_runs_the_scenes_controller(elf: &[u8]) {
    let host = host_configure();
    let file = std::fs::read(board_dir().join("scene.configure")).unwrap();
    assert_eq!(
        file, host,
        "boards/nucleo-f446re/scene.configure is not scenes/line-juggler.toml's Configure: \
         run `dexter board scenes/line-juggler.toml --write boards/nucleo-f446re/scene.configure`"
    );
    let addr = symbol(elf, "DEXTER_SCENE_CONFIGURE").expect("DEXTER_SCENE_CONFIGURE in the image");
    let len = symbol_size(elf, "DEXTER_SCENE_CONFIGURE").unwrap() as usize;
    assert_eq!(len, host.len(), "the linked frame's length");
    let linked = bytes_at(elf, addr, len).expect("the frame's bytes in a loaded section");
    assert_eq!(
        linked,
        &host[..],
        "the board's built-in Configure is not the host's"
    );
}

/// The image's functions by address, each with the addresses its direct calls and tail
/// branches (`bl`, `b.w`, `b` to another function) go to, in program order, and the
/// label `llvm-objdump -d` gives each (one of its names, where several alias it).
struct CallGraph {
    calls: HashMap<u64, Vec<u64>>,
    labels: HashMap<String, u64>,
}

fn hex(t: &str) -> Option<u64> {
    u64::from_str_radix(t.trim().trim_start_matches("0x"), 16).ok()
}

fn call_graph(elf: &Path) -> CallGraph {
    let objdump = dexter_sim::hil::llvm_tool("llvm-objdump").unwrap_or_else(|e| panic!("{e}"));
    let out = Command::new(objdump)
        .args(["-d", "--no-show-raw-insn", "--triple=thumbv7em-none-eabihf"])
        .arg(elf)
        .output()
        .expect("llvm-objdump runs");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let mut g = CallGraph {
        calls: HashMap::new(),
        labels: HashMap::new(),
    };
    let mut current = 0;
    for line in String::from_utf8_lossy(&out.stdout).lines() {
        let label = line.strip_suffix(">:").and_then(|l| l.split_once(" <"));
        if let Some((addr, name)) = label.and_then(|(a, n)| Some((hex(a)?, n))) {
            current = addr;
            g.labels.insert(name.to_string(), addr);
            g.calls.entry(addr).or_default();
            continue;
        }
        let mut fields = line.split('\t').map(str::trim);
        let op = fields.nth(1).unwrap_or("");
        let operand = fields.next().unwrap_or("");
        let to_function = operand.contains('<') && !operand.contains('+');
        if matches!(op, "bl" | "b.w" | "b") && to_function {
            if let Some(t) = operand.split_whitespace().next().and_then(hex) {
                g.calls.entry(current).or_default().push(t);
            }
        }
    }
    g
}

/// Whether the function at `entry`'s first call is `goal`, or goes to a function whose
/// first call is (a few levels down: cortex-m-rt's trampolines, the handlers they call).
fn first_call_reaches(g: &CallGraph, entry: u64, goal: u64) -> bool {
    let mut f = entry;
    for _ in 0..4 {
        match g.calls.get(&f).and_then(|calls| calls.first()) {
            Some(&t) if t == goal => return true,
            Some(&t) => f = t,
            None => return false,
        }
    }
    false
}

/// The fault paths, read from the linked image where the emulator cannot show them (it
/// does not model TIM1, the GPIOs or the IWDG; `host-sim/tests/board_hil.rs` shows the
/// paths it can run end in the motor cut): the HardFault (where a stack overflow and a
/// panic's `udf` end), the unhandled-interrupt handler, the NMI, both limit switches'
/// interrupts (EXTI0, EXTI1) and both panic handlers call `dexter_motor_off` before
/// anything else; the watchdog is fed from the control
/// task (TIM2's handler) and nowhere else, so a hung control task is reset.
fn assert_every_fault_path_cuts_the_motor_first(elf: &Path) {
    let g = call_graph(elf);
    let bytes = std::fs::read(elf).unwrap();
    let addr = |name: &str| {
        symbol(&bytes, name)
            .map(|a| a & !1) // the Thumb bit
            .or_else(|| g.labels.get(name).copied())
            .unwrap_or_else(|| panic!("no {name} in the image"))
    };
    let motor_off = addr("dexter_motor_off");
    let panic_handler = g
        .labels
        .keys()
        .find(|k| k.contains("rust_begin_unwind"))
        .expect("a panic handler")
        .clone();
    for entry in [
        "HardFault",
        "DefaultHandler",
        "NonMaskableInt",
        "EXTI0",
        "EXTI1",
        "_defmt_panic",
        &panic_handler,
    ] {
        assert!(
            first_call_reaches(&g, addr(entry), motor_off),
            "{entry} does not cut the motor first: it calls {:x?}",
            g.calls.get(&addr(entry))
        );
    }
    let feed = addr("dexter_feed_watchdog");
    let feeders: Vec<u64> = g
        .calls
        .iter()
        .filter(|(_, calls)| calls.contains(&feed))
        .map(|(&f, _)| f)
        .collect();
    assert_eq!(feeders, [addr("TIM2")], "the watchdog's feeders");
}

/// DBGMCU's values in the linked image (`fault::DEXTER_DBGMCU`, written at init; the
/// emulator, which does not model DBGMCU, shows that the three registers are written,
/// `host-sim/tests/board_hil.rs`), against RM0390 sec. 33.16.2-4: `CR` keeps the debug
/// port up in sleep, stop and standby (bits 0, 1, 2); while the core is halted `APB1_FZ`
/// stops TIM2 (bit 0) and the IWDG (bit 12), `APB2_FZ` stops TIM1, the motor's PWM (bit 0).
fn assert_a_halted_core_stops_the_motor_and_the_watchdog(elf: &[u8]) {
    let addr = symbol(elf, "DEXTER_DBGMCU").expect("DEXTER_DBGMCU in the image");
    assert_eq!(symbol_size(elf, "DEXTER_DBGMCU"), Some(12));
    let words: Vec<u32> = bytes_at(elf, addr, 12)
        .expect("DEXTER_DBGMCU's bytes")
        .chunks(4)
        .map(|w| u32::from_le_bytes(w.try_into().unwrap()))
        .collect();
    let (cr, apb1, apb2) = (words[0], words[1], words[2]);
    let (dbg_sleep, dbg_stop, dbg_standby) = (1 << 0, 1 << 1, 1 << 2);
    assert_eq!(
        cr & (dbg_sleep | dbg_stop | dbg_standby),
        0b111,
        "DBGMCU_CR {cr:#x}"
    );
    let (dbg_tim2_stop, dbg_iwdg_stop, dbg_tim1_stop) = (1 << 0, 1 << 12, 1 << 0);
    assert_eq!(
        apb1 & dbg_tim2_stop,
        dbg_tim2_stop,
        "APB1_FZ {apb1:#x}: TIM2"
    );
    assert_eq!(
        apb1 & dbg_iwdg_stop,
        dbg_iwdg_stop,
        "APB1_FZ {apb1:#x}: IWDG"
    );
    assert_eq!(
        apb2 & dbg_tim1_stop,
        dbg_tim1_stop,
        "APB2_FZ {apb2:#x}: TIM1"
    );
}

/// One test, so the image is built once: golden sizes, budgets, documents, the scene.
#[test]
fn the_board_image_builds_fits_its_budgets_and_matches_the_expected_sizes() {
    let elf = board_elf();
    let bytes = std::fs::read(&elf).unwrap();
    let marker = b"DEXTER_QEMU_HSI_IMAGE";
    assert!(
        !bytes.windows(marker.len()).any(|w| w == marker),
        "the real image carries the emulator's marker (scripts/run-target.sh would not flash it)"
    );
    assert_the_board_runs_the_scenes_controller(&bytes);
    assert_every_fault_path_cuts_the_motor_first(&elf);
    assert_a_halted_core_stops_the_motor_and_the_watchdog(&bytes);
    let s = sizes(&elf);
    let actual = sizes_text(&s);
    let expected_path = board_dir().join("expected/sizes.txt");
    if bless() {
        std::fs::write(&expected_path, &actual).unwrap();
    }
    let expected = std::fs::read_to_string(&expected_path).unwrap_or_else(|e| {
        panic!(
            "{}: {e} (DEXTER_BLESS=1 creates it)",
            expected_path.display()
        )
    });
    assert_eq!(
        expected, actual,
        "the board image's sizes changed (DEXTER_BLESS=1 regenerates on purpose)"
    );
    let flash = s.text + s.data;
    assert!(flash <= FLASH_BUDGET, "flash {flash} > {FLASH_BUDGET}");
    let ram = s.data + s.bss + s.stack_reserved;
    assert!(ram <= RAM_BUDGET, "RAM {ram} > {RAM_BUDGET}");
    assert_eq!(s.stack_reserved, 6 * 1024, "the QEMU image's reservation");
    let table = size_table(&expected);
    check_block(&root().join("firmware/README.md"), &table);
    check_block(&root().join("BENCHMARKS.md"), &table);
}

/// Every cargo alias that builds or runs a firmware image (`.cargo/config.toml`, as
/// firmware/README.md documents them: `fw`, `board-flash`, `board-emu`, `board-calibrate`
/// and their `-build` forms) builds from the workspace root. A `run` alias is built as
/// `build` with the same arguments: running flashes a board through a probe, or boots QEMU
/// until it is stopped (the emulated board's boot is `host-sim/tests/board_hil.rs`'s, the
/// runner's choice of machine the test below). The host alias `board-hil` is the CLI's
/// `run SCENE --hil --port`, which `board_hil.rs` runs.
#[test]
fn every_firmware_alias_builds_from_the_workspace_root() {
    let config = std::fs::read_to_string(root().join(".cargo/config.toml")).unwrap();
    let config: toml::Table = toml::from_str(&config).expect(".cargo/config.toml parses");
    let aliases = config["alias"].as_table().expect("an [alias] table");
    let mut built = Vec::new();
    for (name, value) in aliases {
        let command = value.as_str().expect("an alias is one string");
        let words: Vec<&str> = command
            .split_whitespace()
            .take_while(|&w| w != "--")
            .collect();
        if !words.contains(&TARGET) {
            continue;
        }
        let (verb, args) = words.split_first().unwrap();
        assert!(
            matches!(*verb, "run" | "build"),
            "alias {name}: `{command}`"
        );
        let _one_at_a_time = BUILD.lock().unwrap_or_else(|e| e.into_inner());
        cargo(&[&["build"], args].concat(), &format!("alias {name}"));
        built.push(name.clone());
    }
    for documented in ["fw", "board-flash", "board-emu", "board-calibrate"] {
        assert!(
            built.iter().any(|b| b == documented),
            "no alias {documented}: {built:?}"
        );
    }
}

/// The camera-side sketch (`boards/nucleo-f446re/camera/frames.py`) encodes the frame the
/// board's parser reads: its self-test checks the drivers' test vector byte for byte.
#[test]
fn the_camera_sketch_encodes_the_drivers_frame() {
    let out = Command::new("python3")
        .arg(board_dir().join("camera/frames.py"))
        .arg("--selftest")
        .output()
        .expect("python3 runs");
    assert!(
        out.status.success(),
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
}

/// The workspace's runner (`scripts/run-target.sh`, `.cargo/config.toml`) picks the machine
/// by image, so that `cargo run -p dexter-nucleo-f446re` from the root flashes the board
/// instead of booting the F446 image in the QEMU image's mps2-an386: run on stand-in
/// images with `probe-rs` and `qemu-system-arm` replaced by stubs that record their
/// arguments.
#[test]
fn the_runner_flashes_the_board_image_and_emulates_the_others() {
    use std::os::unix::fs::PermissionsExt;
    let dir = std::env::temp_dir().join(format!("dexter-runner-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    for tool in ["probe-rs", "qemu-system-arm"] {
        let stub = dir.join(tool);
        let script = format!(
            "#!/bin/sh\necho \"{tool} $*\" > \"{}/called\"\n",
            dir.display()
        );
        std::fs::write(&stub, script).unwrap();
        std::fs::set_permissions(&stub, std::fs::Permissions::from_mode(0o755)).unwrap();
    }
    let image = |name: &str, text: &[u8]| {
        let p = dir.join(name);
        std::fs::write(&p, text).unwrap();
        p
    };
    let cases = [
        (
            image("dexter-nucleo-f446re", b"\x7fELF board"),
            "probe-rs run --chip STM32F446RETx",
        ),
        (
            image(
                "dexter-nucleo-f446re-qemu-hsi.elf",
                b"\x7fELF DEXTER_QEMU_HSI_IMAGE",
            ),
            "qemu-system-arm -machine netduinoplus2",
        ),
        (
            image("dexter-mps2-an386", b"\x7fELF qemu"),
            "qemu-system-arm -machine mps2-an386",
        ),
    ];
    for (elf, want) in cases {
        let out = Command::new(root().join("scripts/run-target.sh"))
            .arg(&elf)
            .env("PATH", format!("{}:/usr/bin:/bin", dir.display()))
            .stdout(std::process::Stdio::null())
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let called = std::fs::read_to_string(dir.join("called")).unwrap();
        assert!(
            called.starts_with(want) && called.contains(elf.to_str().unwrap()),
            "{}: ran {called}",
            elf.display()
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}
