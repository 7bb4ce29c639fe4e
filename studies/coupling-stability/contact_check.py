"""The fender contact's prediction (fender.py, lead 1.5 dt = linear_model 'pred') with its default
stiffness 2e6 N/m and damping 4e5 N s/m on the ASD tug's bow (smallest effective mass 1.85e5 kg)
against a heavy hull (S-175, 7.4e6 kg): growth rate (1/s) of the contact mode while in contact
(linearised, contact held closed), and the same with the Jacobian coupling."""
from linear_model import Exchange
m_a, m_b, k, c = 1.85e5, 7.38e6, 2.0e6, 4.0e5
print("rate Hz   pred      jac_pred   exact")
for r in (1, 2, 3, 5, 10, 20, 50):
    g = [Exchange(s, 1.0 / r, m_a, 0.0, k, c, m_b=m_b).growth_rate() for s in ("pred", "jac_pred", "exact")]
    print(f"{r:6g} " + " ".join(f"{x:9.3f}" for x in g))
