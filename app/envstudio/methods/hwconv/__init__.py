"""Method ``hwconv`` (seed 004 §5.2): radii (no GL), convolution (GPU passes), method,
accuracy and bench (seed 004's tables), figures (Figure 3), plugin."""
