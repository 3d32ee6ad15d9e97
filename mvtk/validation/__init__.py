"""mvtk.validation (see DESIGN.md)."""

__all__: list[str] = []
