"""The noise law of a case as the product applies it (issue 32): `apply` puts a fitted law (config
`noise_model`) into a results table's noise SD columns. Fitting it to seed repeats is the lab's
(spreadlab.noise_law: `cells`, `fit`, `leave_one_out`, `refit`, `plot`, `counting`)."""
