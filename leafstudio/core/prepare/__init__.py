"""core/prepare."""
