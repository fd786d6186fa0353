"""Ground-truth annotation: tracks of keyframed boxes (`model`), their store with a journal
(`store`), exchange formats (`formats`) and their use as the evaluation's truth (`truth`)."""
