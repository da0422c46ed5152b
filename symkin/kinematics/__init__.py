"""The paper's kinematics (sections 3 to 5) as sympy expressions: positions and loop closure
(`positions`), the rigid linkage's closed-form dyads (`dyads`), section 5's scalar loop equations
(`loop_equations`), the symbolic deviation at every level (`analysis`), the cheaper variants a
user can trade (`variants`) and the closures whose implicit-function theorem gives the
sensitivities (`sensitivity`)."""
