"""Native reference engine of the twin: the bench paper's dependent-coordinate multibody model
(S003 §3): natural coordinates, R-matrix velocity transformation, Lankarani–Nikravesh contact
with regularized Coulomb friction, symplectic Euler; plus the penalty formulation it is
compared with (§4.1). See :mod:`twin.reference.model` for the formulation."""
