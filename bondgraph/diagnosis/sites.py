"""Where an effect can act in a user's model: its sites.

A *site* is a place of the bond graph where a missing effect can be put: a storage element's
law (a C: a spring, a capacitor; an I: a mass, an inductance), a dissipative element's law (an
R: a damper, a resistor), the drive (the model's input) or the sensor (its output).  Elements
that play the same part are one site, so that an effect is fitted on all of them together:
the elements sharing a *role* (``model.tag(element, role)``, e.g. the ``stiffness`` of every
layer of a stack) and, among untagged ones, the elements of repeated components that share
their local name (``L1.Re``, ``L2.Re``, ... are the site ``*.Re``).

The generic effect kinds (:mod:`.laws`, :mod:`.modes`) act at sites whose role is one of
:data:`GENERIC_ROLES` (none, or a mechanical role the framework knows); a domain library may
give other roles (a piezo layer's ``polarization``) and its own candidates for them.
"""

from __future__ import annotations

from dataclasses import dataclass

from ..model.elements import C, I, R
from ..model.graph import Model

#: roles at which the framework's generic effect kinds act (None: an untagged element)
GENERIC_ROLES = (None, "stiffness", "damping", "inertia")

#: the element kind of each site kind
KINDS = {"C": C, "I": I, "R": R}


@dataclass(frozen=True)
class Site:
    """A place where an effect can act.

    Parameters
    ----------
    name : str
        How reports name it: the element's name (also for a role only one element plays),
        the role shared by its elements, or ``*.<local name>`` for the elements of repeated
        components.
    kind : str
        ``"C"``, ``"I"`` or ``"R"`` (an element law), ``"drive"`` or ``"sensor"``.
    elements : tuple of str
        The model's elements at the site (empty for the drive and the sensor).
    role : str or None
        The role the elements share, if any.
    """

    name: str
    kind: str
    elements: tuple[str, ...] = ()
    role: str | None = None

    def present(self, model: Model) -> bool:
        """Whether every element of the site is still in ``model`` with its kind.

        Parameters
        ----------
        model : Model
            The model to look in (e.g. one extended by an earlier cause).

        Returns
        -------
        bool
            True when every element is there with its kind (always for the drive and the
            sensor).
        """
        cls = KINDS.get(self.kind)
        return cls is None or all(isinstance(model.elements.get(e), cls) for e in self.elements)


def _local(name: str) -> str:
    return name.rsplit(".", 1)[-1]


def element_sites(model: Model, kinds: tuple[str, ...] = ("C", "I", "R")) -> list[Site]:
    """The element sites of ``model`` (see the module docstring), in the order their first
    element was added: one per role, one per local name shared by several untagged elements of
    components, and one per other untagged element.

    Parameters
    ----------
    model : Model
        The model whose elements are grouped.
    kinds : tuple of str
        The element kinds wanted (``"C"``, ``"I"``, ``"R"``).

    Returns
    -------
    list of Site
    """
    groups: dict[tuple, list[str]] = {}
    for name, el in model.elements.items():
        kind = next((k for k in kinds if type(el) is KINDS[k]), None)
        if kind is None:
            continue
        role = getattr(el, "role", None)
        if role is not None:
            key = (kind, "role", role)
        elif "." in name:
            key = (kind, "local", _local(name))
        else:
            key = (kind, "element", name)
        groups.setdefault(key, []).append(name)
    out = []
    for (kind, how, label), names in groups.items():
        if how == "local" and len(names) == 1:
            out.append(Site(names[0], kind, tuple(names)))
        elif how == "local":
            out.append(Site(f"*.{label}", kind, tuple(names)))
        elif how == "role" and len(names) == 1:  # a role one element plays: named by it
            out.append(Site(names[0], kind, tuple(names), label))
        else:
            out.append(Site(label, kind, tuple(names), label if how == "role" else None))
    return out


def generic_sites(model: Model, kind: str) -> list[Site]:
    """The element sites of one kind at which the generic effect kinds act (roles in
    :data:`GENERIC_ROLES`).

    Parameters
    ----------
    model : Model
        The model.
    kind : {"C", "I", "R"}
        The element kind.

    Returns
    -------
    list of Site
        The sites, in the order their first element was added.
    """
    return [s for s in element_sites(model, (kind,)) if s.role in GENERIC_ROLES]


#: a site of at most this many elements (springs or masses sharing a role) gets one candidate
#: per element for effects that sit in one element (a loop in one spring's law, a mode in one
#: mass), not in all of them alike
PER_ELEMENT = 4


def each_element(site: Site) -> list[Site]:
    """One site per element of ``site`` (named by the element) when it shares a role among at
    most :data:`PER_ELEMENT` elements, else ``site`` itself (its first element stands for it).

    Parameters
    ----------
    site : Site
        A site of one or more elements.

    Returns
    -------
    list of Site
        The sites to try an effect of one element at.
    """
    if 1 < len(site.elements) <= PER_ELEMENT:
        return [Site(el, site.kind, (el,), site.role) for el in site.elements]
    return [site]
