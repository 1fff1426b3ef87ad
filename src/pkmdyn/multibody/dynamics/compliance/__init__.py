"""Link and joint compliance in the dynamics: the beam model of elastic bodies and the joints'
springs (:mod:`.reactions`), which make an over-constrained mechanism's joint reactions unique
(least complementary energy) and give the stiffness analysis its members
(:mod:`pkmdyn.multibody.analyses.stiffness`); the beams' energy in one compiled pass per sample
(:mod:`._compliance_kernels`)."""
