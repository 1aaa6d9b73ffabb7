//! dexter on a NUCLEO-F446RE (STM32F446RE, Cortex-M4F at 180 MHz), an RTIC 2 app.
//!
//! Two ways to run, chosen by the virtual COM port (USART2, the ST-LINK's VCP):
//! - **juggling** (from reset): TIM2's update interrupt runs one control period at
//!   [`CONTROL_RATE_HZ`] (hardware task `control`, priority 2): the rig's sensors (encoder,
//!   camera), the core's line-juggler `step` (the same `dexter_core::control::Controller`
//!   the simulator and the QEMU image run), the motor; the period's deadline is checked and
//!   an overrun answered with the core's safe command (`dexter_rig::periodic`). Once a
//!   second the period task hands a snapshot to `telemetry` (software task, priority 1),
//!   which logs it with defmt over RTT. The controller is the scene's chosen at build time
//!   ([`DEXTER_SCENE_CONFIGURE`], `dexter board SCENE --write FILE`), not a default tuning.
//! - **hardware in the loop**: the first valid `Configure` frame a host sends on the VCP
//!   (decoded and accepted by the lock-step server; noise or a UART error does not) ends
//!   the juggling loop for good (the motor is parked, duty 0; TIM2 keeps ticking only to
//!   keep it parked and feed the watchdog): `idle` runs the
//!   board-neutral lock-step server (`dexter_firmware::server::Server`) on the VCP, exactly
//!   as the QEMU image does, and the host's simulated plant closes the loop
//!   (`dexter run SCENE --hil --port /dev/ttyACM0`). After the host's `Stop` the board
//!   resets, back to juggling.
//!
//! The receive interrupts of both UARTs (priority 3) only move bytes into rings
//! (`dexter_firmware::uart`). The control task alone feeds the independent watchdog, and
//! every fault path cuts the motor first (`fault`); with the `qemu-hsi` feature the same
//! image runs on the internal oscillator in QEMU's netduinoplus2 (firmware/README.md,
//! "Emulation").
#![no_std]
#![no_main]
#![deny(unsafe_op_in_unsafe_fn)]

use defmt_rtt as _; // global logger: defmt over RTT, read by probe-rs
                    // The panic handlers are `fault`'s: motor off first.

#[cfg(feature = "calibrate")]
mod calibrate;
mod fault;
#[cfg(feature = "qemu-hsi")]
mod fault_hooks;
mod limits;
mod report;
mod rig;
mod tick;

use core::sync::atomic::AtomicBool;

/// The control rate of the juggling loop, Hz: the line controller's `dt_s` must be its
/// inverse (checked at start).
pub const CONTROL_RATE_HZ: u32 = 500;
/// Core clock, Hz (HSE 8 MHz from the ST-LINK's MCO, PLL to the F446's 180 MHz maximum; with
/// the `qemu-hsi` feature, the 16 MHz internal oscillator, no PLL). The control period is
/// counted from the frozen clocks the HAL reports, not from this constant.
#[cfg(not(feature = "qemu-hsi"))]
pub const SYSCLK_HZ: u32 = 180_000_000;
/// Core clock, Hz: the 16 MHz internal oscillator (feature `qemu-hsi`).
#[cfg(feature = "qemu-hsi")]
pub const SYSCLK_HZ: u32 = 16_000_000;
/// The host link's rate, Bd (the ST-LINK/V2-1 VCP carries up to 2 MBd).
pub const VCP_BAUD: u32 = 921_600;
/// The independent watchdog's timeout, ms: 10 control periods (the LSI that clocks it is
/// 17 to 47 kHz on the F4, so the real timeout is 7 to 19 ms). Fed by the control task only.
pub const WATCHDOG_MS: u32 = 20;

/// The calibration image (feature `calibrate`): the motor parked from reset, the sensors
/// read raw (`calibrate`).
const CALIBRATING: bool = cfg!(feature = "calibrate");

/// Set when the lock-step server accepts a host's `Configure` ([`HostSession`]): a host
/// drives the board from now. (Unmangled for a debugger and the emulator test.)
#[no_mangle]
static DEXTER_HOST_SESSION: AtomicBool = AtomicBool::new(false);
use DEXTER_HOST_SESSION as HOST_SESSION;

/// Marks the `qemu-hsi` image, so that the workspace's runner (`scripts/run-target.sh`)
/// boots it in QEMU's netduinoplus2 instead of flashing it.
#[cfg(feature = "qemu-hsi")]
#[no_mangle]
#[used]
pub static DEXTER_QEMU_HSI_IMAGE: u8 = 1;

/// The scene's `Configure` frame the stand-alone loop runs (`build.rs`:
/// `DEXTER_BOARD_CONFIGURE`, from `dexter board SCENE --write FILE`), the bytes a host would
/// send. Kept under this symbol so that `tests/board.rs` can compare it with the host's.
#[no_mangle]
#[used]
pub static DEXTER_SCENE_CONFIGURE: [u8; SCENE_CONFIGURE_LEN] =
    *include_bytes!(concat!(env!("OUT_DIR"), "/scene.configure"));
const SCENE_CONFIGURE_LEN: usize =
    include_bytes!(concat!(env!("OUT_DIR"), "/scene.configure")).len();

/// Feed the independent watchdog: called by the control task only (the image check in
/// `tests/board.rs` finds no other caller), so a hung control task resets the part.
#[inline(never)]
#[no_mangle]
pub extern "Rust" fn dexter_feed_watchdog(
    watchdog: &mut stm32f4xx_hal::watchdog::IndependentWatchdog,
) {
    watchdog.feed();
}

/// Ends the stand-alone loop when a host's `Configure` is accepted.
pub struct HostSession;

impl dexter_firmware::server::SessionHook for HostSession {
    fn configured(&mut self, _: dexter_core::protocol::Kind) {
        HOST_SESSION.store(true, core::sync::atomic::Ordering::Relaxed);
    }
}

/// The stand-alone loop's controller parameters: [`DEXTER_SCENE_CONFIGURE`] decoded as a
/// host's `Configure` is (a frame that is not a line juggler's stops the board at reset).
fn scene_params() -> dexter_core::control::ControllerParams {
    use dexter_core::protocol::{decode, Partial, MAX_FRAME_LEN};
    use dexter_firmware::hosted::Params;
    use dexter_firmware::server::HostMessage;
    let mut buf = [0u8; MAX_FRAME_LEN];
    // Safety: a volatile read, so the bytes come from flash as linked (not constant-folded).
    let frame = unsafe { core::ptr::read_volatile(&DEXTER_SCENE_CONFIGURE) };
    let body = frame.split_last().map_or(&[][..], |(_, body)| body);
    let Some(scratch) = buf.get_mut(..body.len()) else {
        defmt::panic!("the scene's Configure frame is longer than a frame")
    };
    scratch.copy_from_slice(body);
    match decode::<HostMessage>(scratch) {
        Ok(HostMessage::Configure(Partial::Hosted(Params::Line(params)))) => params,
        Ok(_) => defmt::panic!("the scene's Configure frame is not a line juggler's"),
        Err(e) => defmt::panic!("the scene's Configure frame does not decode: {}", e),
    }
}

#[rtic::app(device = stm32f4xx_hal::pac, peripherals = true, dispatchers = [SPI1])]
mod app {
    use crate::report::Report;
    use crate::rig::{self, BoardRig, Tim3Encoder, CAMERA_BAUD, PWM_HZ};
    use crate::tick::TickClock;
    use crate::{
        HostSession, CALIBRATING, CONTROL_RATE_HZ, HOST_SESSION, SYSCLK_HZ, VCP_BAUD, WATCHDOG_MS,
    };
    use core::sync::atomic::Ordering;
    use dexter_core::control::{Controller, ControllerParams};
    use dexter_core::fixed_rate::FixedRate;
    use dexter_firmware::board::DwtCycles;
    use dexter_firmware::ring::{ByteRing, Producer};
    use dexter_firmware::server::Server;
    use dexter_firmware::uart::{self as uart_ring, ErrorCount, RingLink, RingReader, RX_RING_LEN};
    use dexter_rig::periodic::{Deadline, Periodic};
    use dexter_rig::rig::Rig;
    use stm32f4xx_hal::pac::{TIM2, USART1, USART2};
    use stm32f4xx_hal::prelude::*;
    use stm32f4xx_hal::rcc::Config as Clocks;
    use stm32f4xx_hal::serial::{Config as SerialConfig, Rx, Serial, Tx};
    use stm32f4xx_hal::syscfg::SysCfgExt;
    use stm32f4xx_hal::timer::{CounterHz, Event, Flag};
    use stm32f4xx_hal::watchdog::IndependentWatchdog;

    static VCP_RING: ByteRing<RX_RING_LEN> = ByteRing::new();
    static CAMERA_RING: ByteRing<RX_RING_LEN> = ByteRing::new();
    static VCP_ERRORS: ErrorCount = ErrorCount::new();
    static CAMERA_ERRORS: ErrorCount = ErrorCount::new();

    #[shared]
    struct Shared {
        report: Report,
        /// Nothing: locked by `control` around the core's step, its ceiling (the receive
        /// interrupts', 3) keeps them out of the measured window without masking faults.
        step_window: (),
    }

    #[local]
    struct Local {
        periodic: Periodic<Controller>,
        rig: BoardRig,
        tick: CounterHz<TIM2>,
        steps: DwtCycles,
        vcp_rx: Rx<USART2, u8>,
        vcp_ring: Producer<'static, RX_RING_LEN>,
        camera_rx: Rx<USART1, u8>,
        camera_ring: Producer<'static, RX_RING_LEN>,
        server: Server<RingLink<Tx<USART2, u8>>, DwtCycles, HostSession>,
        watchdog: IndependentWatchdog,
        /// Reset by the watchdog: the motor stays parked until a power cycle or a reset.
        parked: bool,
    }

    #[init]
    fn init(cx: init::Context) -> (Shared, Local) {
        let mut core = cx.core;
        let dp = cx.device;
        #[cfg(not(feature = "qemu-hsi"))]
        let clocks = Clocks::hse(8.MHz())
            .bypass_hse_oscillator()
            .sysclk(SYSCLK_HZ.Hz());
        #[cfg(feature = "qemu-hsi")]
        let clocks = Clocks::hsi().sysclk(SYSCLK_HZ.Hz());
        let watchdog_reset = dp.RCC.csr().read().wdgrstf().bit_is_set();
        #[cfg(feature = "qemu-hsi")]
        let watchdog_reset = crate::fault_hooks::take_emulated_watchdog_reset() || watchdog_reset;
        dp.RCC.csr().modify(|_, w| w.rmvf().set_bit());
        crate::fault::freeze_on_halt(&dp.DBGMCU);
        crate::fault::guard_stack(&mut core.MPU);
        let mut rcc = dp.RCC.freeze(clocks);
        let steps = DwtCycles::new(&mut core.DCB, &mut core.DWT);
        let server_steps = DwtCycles::new(&mut core.DCB, &mut core.DWT);
        let gpioa = dp.GPIOA.split(&mut rcc);
        let gpiob = dp.GPIOB.split(&mut rcc);
        let gpioc = dp.GPIOC.split(&mut rcc);
        let mut syscfg = dp.SYSCFG.constrain(&mut rcc);
        let mut exti = dp.EXTI;
        let limits =
            crate::limits::LimitSwitches::new(gpioc.pc0, gpioc.pc1, &mut syscfg, &mut exti);
        let limit_open = limits.open();

        let (Some((vcp_ring, vcp_consumer)), Some((camera_ring, camera_consumer))) =
            (uart_ring::split(&VCP_RING), uart_ring::split(&CAMERA_RING))
        else {
            defmt::panic!("receive rings split twice")
        };
        let vcp_config = SerialConfig::default().baudrate(VCP_BAUD.bps());
        let Ok(mut vcp) = Serial::new(dp.USART2, (gpioa.pa2, gpioa.pa3), vcp_config, &mut rcc)
        else {
            defmt::panic!("USART2 cannot run at {=u32} Bd", VCP_BAUD)
        };
        vcp.listen(stm32f4xx_hal::serial::Event::RxNotEmpty);
        let (vcp_tx, vcp_rx) = vcp.split();
        let camera_config = SerialConfig::default().baudrate(CAMERA_BAUD.bps());
        let Ok(mut camera_rx) = Serial::rx(dp.USART1, gpioa.pa10, camera_config, &mut rcc) else {
            defmt::panic!("USART1 cannot run at {=u32} Bd", CAMERA_BAUD)
        };
        camera_rx.listen();

        // Safety: TIM1's registers, before the PWM channel takes it: OSSI and OIS1 only.
        crate::fault::idle_level_when_off(unsafe { &*stm32f4xx_hal::pac::TIM1::ptr() });
        let (_, (pwm, ..)) = dp.TIM1.pwm_hz(PWM_HZ.Hz(), &mut rcc);
        let mut pwm = pwm.with(gpioa.pa8);
        pwm.enable();
        let dir = gpiob.pb5.into_push_pull_output();
        let encoder = Tim3Encoder(dp.TIM3.qei((gpioa.pa6, gpioa.pa7), &mut rcc));

        let params = crate::scene_params();
        let (rig, periodic) = juggler(
            params,
            rcc.clocks.sysclk().raw(),
            encoder,
            RingReader::new(camera_consumer, &CAMERA_ERRORS),
            pwm,
            dir,
        );
        let mut tick = dp.TIM2.counter_hz(&mut rcc);
        if tick.start(CONTROL_RATE_HZ.Hz()).is_err() {
            defmt::panic!("TIM2 cannot tick at {=u32} Hz", CONTROL_RATE_HZ);
        }
        tick.listen(Event::Update);
        defmt::info!(
            "dexter {=str} on NUCLEO-F446RE: sysclk {=u32} Hz, line juggler at {=u32} Hz on TIM2, host link USART2 at {=u32} Bd",
            env!("CARGO_PKG_VERSION"),
            rcc.clocks.sysclk().raw(),
            CONTROL_RATE_HZ,
            VCP_BAUD
        );
        if watchdog_reset {
            defmt::error!("reset by the watchdog: the motor stays parked (HIL still runs)");
        }
        if CALIBRATING {
            defmt::info!("calibration image: the motor stays parked; the sensors are logged raw");
        }
        if limit_open {
            defmt::error!(
                "a limit switch is open at reset: the motor stays parked (HIL still runs)"
            );
        }
        let mut watchdog = IndependentWatchdog::new(dp.IWDG);
        watchdog.start(WATCHDOG_MS.millis());
        let server = Server::with_hook(
            RingLink::new(vcp_consumer, vcp_tx),
            server_steps,
            HostSession,
        );
        let shared = Shared {
            report: Report::default(),
            step_window: (),
        };
        let local = Local {
            periodic,
            rig,
            tick,
            steps,
            vcp_rx,
            vcp_ring,
            camera_rx,
            camera_ring,
            server,
            watchdog,
            parked: watchdog_reset || limit_open || CALIBRATING,
        };
        (shared, local)
    }

    /// The juggling loop's controller and rig; a calibration or parameter the drivers or
    /// the core refuse stops the board here, with the reason in the log.
    fn juggler(
        params: ControllerParams,
        sysclk_hz: u32,
        encoder: Tim3Encoder,
        camera: RingReader,
        pwm: rig::MotorPwm,
        dir: rig::MotorDir,
    ) -> (BoardRig, Periodic<Controller>) {
        let rate_error = (params.dt_s * CONTROL_RATE_HZ as f32 - 1.0).abs();
        if rate_error > 1e-6 {
            defmt::panic!(
                "the controller's dt_s {=f32} s is not 1/{=u32} Hz",
                params.dt_s,
                CONTROL_RATE_HZ
            );
        }
        let rig = match rig::rig(encoder, camera, pwm, dir, params.dt_s) {
            Ok(rig) => rig,
            Err(e) => defmt::panic!("rig calibration refused: {}", e),
        };
        let controller = match Controller::new(params) {
            Ok(c) => c,
            Err(e) => defmt::panic!("controller parameters refused: {}", e),
        };
        let Some(periodic) = Periodic::new(controller, sysclk_hz / CONTROL_RATE_HZ) else {
            defmt::panic!("zero control period")
        };
        (rig, periodic)
    }

    /// The host link's receive interrupt: bytes into the ring (the lock-step server in
    /// `idle` decodes them; only an accepted `Configure` starts a host session).
    #[task(binds = USART2, priority = 3, local = [vcp_rx, vcp_ring], shared = [step_window])]
    fn vcp_receive(cx: vcp_receive::Context) {
        let _ = uart_ring::on_receive(cx.local.vcp_rx, cx.local.vcp_ring, &VCP_ERRORS);
    }

    /// The lower limit switch opened: motor off for good (`limits`).
    #[task(binds = EXTI0, priority = 4)]
    fn lower_limit(_: lower_limit::Context) {
        crate::fault::limit_switch_opened("lower")
    }

    /// The upper limit switch opened: motor off for good (`limits`).
    #[task(binds = EXTI1, priority = 4)]
    fn upper_limit(_: upper_limit::Context) {
        crate::fault::limit_switch_opened("upper")
    }

    /// The camera's receive interrupt: bytes into the ring.
    #[task(binds = USART1, priority = 3, local = [camera_rx, camera_ring], shared = [step_window])]
    fn camera_receive(cx: camera_receive::Context) {
        let _last = uart_ring::on_receive(cx.local.camera_rx, cx.local.camera_ring, &CAMERA_ERRORS);
        #[cfg(feature = "qemu-hsi")]
        crate::fault_hooks::on_camera_byte(_last);
    }

    /// One control period on TIM2's tick (see the crate docs).
    /// In a host session (or after a watchdog reset) the task only keeps the motor parked
    /// and feeds the watchdog: the motor is never driven again until reset.
    #[task(binds = TIM2, priority = 2, local = [periodic, rig, tick, steps, watchdog, parked], shared = [report, step_window])]
    fn control(mut cx: control::Context) {
        let local = cx.local;
        crate::dexter_feed_watchdog(local.watchdog);
        if *local.parked || HOST_SESSION.load(Ordering::Relaxed) {
            local.tick.clear_flags(Flag::Update);
            if local.rig.park().is_err() {
                defmt::error!("the motor could not be parked");
            }
            #[cfg(feature = "calibrate")]
            if !HOST_SESSION.load(Ordering::Relaxed) {
                crate::calibrate::sample(local.rig);
            }
            if !*local.parked {
                defmt::info!(
                    "a host configured the board: juggling loop stopped, motor parked, lock-step HIL"
                );
                *local.parked = true;
            }
            return;
        }
        let mut clock = TickClock::take(local.steps, local.tick, &mut cx.shared.step_window);
        let out = local.periodic.period(local.rig, &mut clock);
        let stats = local.periodic.stats();
        if let Deadline::Overrun { ticks_lost } = out.deadline {
            if stats.overruns.is_power_of_two() {
                defmt::warn!(
                    "overrun #{=u32}: the period's work ran past the next tick ({=u32} ticks lost); safe command sent",
                    stats.overruns,
                    ticks_lost
                );
            }
        }
        let report = Report::new(local.periodic, local.rig, &out, VCP_ERRORS.get());
        cx.shared.report.lock(|r| *r = report);
        if stats.periods.is_multiple_of(CONTROL_RATE_HZ) {
            let _ = telemetry::spawn(); // still busy with the last one: skip a report
        }
    }

    /// Once a second: the loop's figures in the log.
    #[task(priority = 1, shared = [report])]
    async fn telemetry(mut cx: telemetry::Context) {
        let report = cx.shared.report.lock(|r| *r);
        report.log();
    }

    /// The lock-step server on the VCP: it blocks (in `wfi`) until a host sends frames.
    #[idle(local = [server])]
    fn idle(cx: idle::Context) -> ! {
        let server = cx.local.server;
        let exit = server.run();
        let stats = server.stats();
        defmt::info!(
            "host session ended: {} after {=u32} steps; resetting",
            exit,
            stats.steps
        );
        cortex_m::peripheral::SCB::sys_reset()
    }
}
