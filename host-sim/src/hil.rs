//! Hardware in the loop: the firmware in QEMU behind [`crate::controller::StepController`].
