"""The mechanism's graph (the paper's section 2): the regular labeling, the skeleton tree and the
structure matrices I, Φ, Ψ (`structure`), and the part of a mechanism that moves requested points
(`pruning`, docs/pruning.md)."""
