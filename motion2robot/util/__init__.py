"""Small shared helpers (no domain logic)."""
