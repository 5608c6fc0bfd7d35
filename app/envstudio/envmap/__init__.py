"""Environment representations on the GPU: cube maps, conversions, mip chains."""
