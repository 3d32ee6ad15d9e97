"""mvtk.reduction (see DESIGN.md)."""

__all__: list[str] = []
