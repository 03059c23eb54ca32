"""Examples shipped with herringbone: the drive-train FMUs (induction_motor, fan_load), their
operating point (drivetrain_operating_point) and a libcosim co-simulation of the drive train
(`python -m herringbone.examples.cosimulate_drivetrain`)."""
