"""Live sessions of `session_recorder`: when a session starts and ends, its input spooled into a bag, and the
whole session identified and stored for its subject."""
