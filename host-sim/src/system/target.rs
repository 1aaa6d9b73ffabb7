//! Controllers outside the simulator: the firmware in QEMU (`--hil`), behind the same
//! [`StepController`] a plant steps in SIL.
//!
//! **This is the one place the CLI reaches the HIL driver** ([`crate::hil`]). A system
//! names its controller kind ([`crate::system::System::Controller`]); `--hil` starts that
//! kind on the target through [`OnTarget::start`] (for every kind the protocol carries,
//! [`Wire`]: `crate::hil::LockStep::<C>::start`), the plant steps it like the core linked
//! in, and [`Target::finish`] stops it and returns the [`HilReport`]. A new controller kind
//! the firmware hosts needs nothing here.

use super::{Failure, NoController};
use crate::controller::{ControllerError, HilReport, StepController};
use crate::hil::LinkKind;
use dexter_core::fixed_rate::FixedRate;
use dexter_core::protocol::Wire;
use std::path::PathBuf;

/// The options of `--hil` as given on the command line (the doc comment of each field is
/// its `--help` line; a relative `--firmware` is taken from the current directory).
#[derive(clap::Args, Clone, Debug, Default, PartialEq)]
pub struct HilRequest {
    /// Firmware ELF for --hil (default: the release build in target/).
    #[arg(long, value_name = "PATH", requires = "hil")]
    pub firmware: Option<PathBuf>,
    /// Plant link for --hil.
    #[arg(long, value_enum, requires = "hil")]
    pub link: Option<LinkKind>,
    /// Instruction budget per control step for --hil (0 = no budget).
    #[arg(long, value_name = "N", requires = "hil")]
    pub budget: Option<u32>,
    /// Fraction of host-to-device bytes corrupted for --hil, in [0, 1].
    #[arg(long, value_name = "F", requires = "hil")]
    pub corrupt_rate: Option<f64>,
    /// HIL against a real board on this serial port (e.g. /dev/ttyACM0) instead of QEMU.
    #[arg(long, value_name = "PATH", requires = "hil", conflicts_with_all = ["firmware", "link"])]
    pub port: Option<PathBuf>,
}

/// `--link semihosting|uart`: the HIL driver's own [`LinkKind`], as clap parses it.
impl clap::ValueEnum for LinkKind {
    fn value_variants<'a>() -> &'a [Self] {
        &[LinkKind::Semihosting, LinkKind::Uart]
    }

    fn to_possible_value(&self) -> Option<clap::builder::PossibleValue> {
        Some(clap::builder::PossibleValue::new(match self {
            LinkKind::Semihosting => "semihosting",
            LinkKind::Uart => "uart",
        }))
    }
}

/// A controller of kind `C` running on a target.
pub trait Target<C: FixedRate>: StepController<C> {
    /// Stop it and report its timing and link figures.
    fn finish(self: Box<Self>) -> Result<HilReport, ControllerError>;
}

/// A controller kind that can run on the target.
pub trait OnTarget: FixedRate + 'static {
    /// Start the firmware hosting this kind with `params`.
    fn start(params: Self::Params, req: &HilRequest) -> Result<Box<dyn Target<Self>>, Failure>;
}

impl<C: Wire> Target<C> for crate::hil::LockStep<C> {
    fn finish(self: Box<Self>) -> Result<HilReport, ControllerError> {
        crate::hil::LockStep::finish(*self)
    }
}

impl<C: Wire + 'static> OnTarget for C {
    fn start(params: Self::Params, req: &HilRequest) -> Result<Box<dyn Target<Self>>, Failure> {
        let opts = hil_options(req)?;
        let lock = crate::hil::LockStep::<C>::start(params, opts).map_err(Failure::run)?;
        Ok(Box::new(lock))
    }
}

impl OnTarget for NoController {
    fn start(_: (), _: &HilRequest) -> Result<Box<dyn Target<Self>>, Failure> {
        Err(Failure::usage(
            "--hil: this system has no controller that runs on a target",
        ))
    }
}

/// The HIL driver's options from the request: the firmware path made absolute (QEMU runs
/// in a directory of its own), the corruption rate checked.
fn hil_options(req: &HilRequest) -> Result<crate::hil::HilOptions, Failure> {
    let mut opts = crate::hil::HilOptions::default();
    if let Some(p) = &req.firmware {
        opts.firmware_elf = std::path::absolute(p)
            .map_err(|e| Failure::usage(format!("--firmware {}: {e}", p.display())))?;
    }
    if let Some(l) = req.link {
        opts.link = l;
    }
    if let Some(b) = req.budget {
        opts.instruction_budget = (b > 0).then_some(b).into();
    }
    if let Some(r) = req.corrupt_rate {
        if !(0.0..=1.0).contains(&r) {
            return Err(Failure::usage(format!(
                "--corrupt-rate must be in [0, 1], got {r}"
            )));
        }
        opts.corrupt_rate = r;
    }
    opts.serial = req.port.clone().map(crate::hil::SerialPortOptions::new);
    Ok(opts)
}
