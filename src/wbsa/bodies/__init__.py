"""bodies stage: virtual bodies (anny), skin mask, anthropometry, random and survey populations."""
