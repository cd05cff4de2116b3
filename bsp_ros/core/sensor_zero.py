"""What an untared force/torque sensor's zero is assumed to be off by (1 SD per sensor axis), in the std."""

# Without a tare the data cannot tell a force offset at the handle from the arm: a vertical one is exactly a
# point mass at the contact point (it moves every static moment), a horizontal one an off-axis mass. So the
# std carries an assumption on the zero: 1 N covers a handle part of 0.1 kg left unzeroed or a sensor zeroed in
# another posture; a cell that zeroes its sensor with the handle on just before the session may state less.
ZERO_SD_N = 1.0
ZERO_SD_NM = 0.02
