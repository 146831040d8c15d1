"""Imperfect revolute joints: clearance, contact laws, the hydrodynamic film, friction,
wear law, bushing profiles."""

from .archard import ArchardWear
from .asperities import GreenwoodTripp
from .clearance_joint import (
    ClearanceJoint,
    ContactHistory,
    centred_state,
    contact_history,
    with_clearance,
)
from .finite_bearing import FiniteBearingFilm
from .finite_table import DynamicFiniteFilm, ShippedFiniteFilm, default_film
from .friction import CoulombFriction
from .kinematics import ContactResult, PinKinematics
from .laws import (
    AbstractContactLaw,
    AbstractPointLaw,
    ElasticFoundation,
    KelvinVoigt,
    LankaraniNikravesh,
)
from .long_bearing import LongBearingFilm
from .lubrication import AbstractFilm, FilmForce, ShortBearingFilm
from .materials import PTFE, STEEL, Material
from .mixed import Lubrication, MixedLubrication
from .profile import BushingProfile

__all__ = [
    "ClearanceJoint", "ContactHistory", "centred_state", "contact_history", "with_clearance",
    "CoulombFriction", "ArchardWear", "ContactResult", "PinKinematics",
    "AbstractContactLaw", "AbstractPointLaw", "ElasticFoundation", "KelvinVoigt",
    "LankaraniNikravesh", "AbstractFilm", "FilmForce", "ShortBearingFilm", "LongBearingFilm",
    "FiniteBearingFilm", "DynamicFiniteFilm", "ShippedFiniteFilm", "default_film",
    "GreenwoodTripp", "Lubrication", "MixedLubrication",
    "PTFE", "STEEL", "Material",
    "BushingProfile",
]
