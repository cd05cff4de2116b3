"""Identification of static moments and passive joint moments: the stacked method (ours) and the paper's."""
