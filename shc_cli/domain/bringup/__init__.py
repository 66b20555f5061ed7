"""Bringing a robot's servos up (``shc hw``): find them (:mod:`shc_cli.hardware.scan`), check where they stand
(:mod:`.check`: present positions against the limits and the standing pose, no motion), jog one joint at a time
and write the confirmed direction and zero back to the robot file (:mod:`.jog`, :mod:`.servo_file`), and serve
emulated buses for a robot's servo map to try all this without hardware (:mod:`.emulate`)."""
