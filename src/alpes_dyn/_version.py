"""The package's version, on the base floor: every floor may import it (``alpes_dyn.__version__`` re-exports it;
a lower floor importing the package's front door ``alpes_dyn/__init__``, which imports the floors above it, would
point up)."""

__version__ = "0.1.0"
