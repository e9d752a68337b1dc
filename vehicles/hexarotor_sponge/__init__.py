"""The Flying Calligrapher's room (Guo et al. 2024): a fully-actuated hexarotor with a one-link arm
writes on a vertical wall with a sponge pen whose line width follows the contact force.

``defaults`` the default figures (plain constants); ``show_section`` the show file's ``hexarotor``
section (defaulting to them) and the wall's reach check; ``params`` the vehicle; ``pen`` force
<-> width; ``allocation`` wrench -> six tilted rotor thrusts; ``world`` MuJoCo, ``fly_settings``
how a plan is flown there (noise, control period; plain data);
``waypoints``/``nlp``/``plan`` contact-aware motion-force planning (eq. 7), ``limits`` its
limits and weights, ``contact_model`` its contact and rotor model, ``solver_cache`` its built
IPOPT solvers, ``diagnosis`` the limit that rules out a period IPOPT finds no trajectory for;
``controller`` hybrid motion-force control (section V), ``disturbance_observer`` its answer to
the wind (ours); ``flight`` the batch closed loop, ``live`` the agent's one;
``metrics``/``report`` Table I's figures; ``kind`` the interface, and the kind object
``vehicles.hexarotor_sponge.kind.KIND``. Importing this package imports nothing else (the show
file reads ``show_section`` and ``defaults`` without loading CasADi or MuJoCo).
"""
