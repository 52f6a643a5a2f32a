"""The sparse pipeline of paper 002 (Algorithm 1), one stage per file, for any problem with 2 to 4 variables:
plan lines, sample them through the store, fit and blend (:mod:`.model`), search, confirm (:mod:`.stage`), refine on
the simulator (:mod:`.refine`), validate on held-out lines (:mod:`.validate`); :mod:`.pipeline` runs them in order."""
