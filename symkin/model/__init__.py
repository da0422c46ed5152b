"""The mechanism as a file describes it (docs/file-format.md): the whitelist expression parser
(`expressions`), the hinge models and their cancellation-free special functions (`hinges`,
`special`), and the file reader with its immutable :class:`~.mechanism.Mechanism` (`mechanism`)."""
