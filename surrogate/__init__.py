"""Mathematics of mechopt: line plans, exponential fitting, Chebyshev blending, the sparse model, its search."""
