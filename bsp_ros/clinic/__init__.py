"""The clinic: the session store, minimal detectable change, and therapist-facing reports."""
