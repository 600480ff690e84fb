"""The package's version, in a module of its own so that every layer can import it without
importing the public API (`rockslide.__init__`)."""

__version__ = "0.1.0"
