"""Thin drivers, one per analysis, on the shared path in fem_forms.model."""
