"""The mechanism as a file describes it (docs/file-format.md): the whitelist expression parser
(`expressions`), the hinge models and their cancellation-free special functions (`hinges`,
`special`), the file's entries (`entries`), the immutable :class:`~.mechanism.Mechanism` with
its value rules (`mechanism`), the rank of its closure at the as-fabricated pose (`closure`), and
the file reader (`reader`, with the checks of one entry in `entry_checks` and the hinges' in
`hinge_entries`)."""
