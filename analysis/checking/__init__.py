"""Properties of a net's runs: the observers of the property patterns, checked on a state space, on the fly, and as a task's interface contract."""
