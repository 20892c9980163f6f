"""``profileopt figures``: reproduce the paper's Figs. 1, 5 and 6 (placeholder, see issue 2)."""
