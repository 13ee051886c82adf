"""patchgen: from an optimal cart-pendulum controller to a checked Comdyna GP-6 patch."""

__version__ = "0.2.0"
