"""Layer 9, scenario files: the shipped ``*.toml`` files and their lookup (``files``), the
dotted-key grammar of ``--set`` and sweep files (``keys``), the schema and validation
(``scenario``)."""

__all__: list[str] = []            # the subpackages are imported by their own names
