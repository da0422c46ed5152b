"""What a user runs on a mechanism: one configuration in any backend (`evaluation`), a generated
evaluator in memory (`compiled`), every artifact written at once (`derive`), the speed/accuracy
trade (`tradeoff`), tolerance stack-ups (`tolerance`) and Monte Carlo sweeps (`sweep`) over the
spreads `variation` parses, and scenes (`scene`)."""
