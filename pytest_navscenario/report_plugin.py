"""pytest hooks for this feature (to be filled in)."""
