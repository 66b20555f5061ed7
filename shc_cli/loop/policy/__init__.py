"""A learned policy on the one run loop: the observation and reward terms (:mod:`.observe`), the three action
spaces (:mod:`.actions`), the policy file (:mod:`.file`, numpy only) and the policy driving a run (:mod:`.drive`).
``shc_cli.gym`` builds its environment on them; ``shc simulate --policy`` and ``shc run-hw --policy`` run a file."""
