"""mvtk.plot (see DESIGN.md)."""

__all__: list[str] = []
