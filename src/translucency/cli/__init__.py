"""Command-line interface: ``translucency --help``."""
