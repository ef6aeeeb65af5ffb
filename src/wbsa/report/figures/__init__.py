"""The report's figures (being split into one module per figure family)."""
