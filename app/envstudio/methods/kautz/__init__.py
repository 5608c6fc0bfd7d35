"""Method ``kautz``: seed 000's single pass (method), its Figures 4 and 6 (figures), plugin."""
