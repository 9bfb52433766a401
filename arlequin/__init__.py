"""arlequin: Arlequin multiscale coupling for computational solid mechanics."""
__version__ = "0.1.0"
