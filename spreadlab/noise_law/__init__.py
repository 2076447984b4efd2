"""The noise law of a case fitted to seed repeats (issue 32): `cells` gathers seed-repeat cells,
`fit` fits ln SD on ln N and ln(h/d) by the chi-square likelihood of the cells' variances, `leave_one_out`
checks it on points it did not see, `refit` refits the config's law, `plot` draws it; `counting`
reads the counting law's constant c from seed repeats. The product applies the fitted law
(spreadmap.noise_law.apply)."""
