"""Materials library and the thickness formulas of process-and-inks.md."""

from __future__ import annotations

import pytest

from rotoprint.errors import ConfigError
from rotoprint.process import builtin_library, cycle_thickness_um, drops_per_mm2, load_materials, wet_film_um
from rotoprint.process.estimates import cycles_for_height, moles_per_m2


def test_build_builtin_materials_follow_the_paper():
    lib = builtin_library()
    assert set(lib.names()) == {"plaster", "silver", "epoxy", "polyamide"}
    pl = lib["plaster"]
    assert [(i.name, i.repeats) for i in pl.inks] == [("ammonium_sulphate", 3), ("calcium_chloride", 1)]
    assert all(i.ph == (6.0, 7.0) for i in pl.inks)
    assert "crystallis" in pl.inks[0].warning
    ag = lib["silver"]
    assert [i.name for i in ag.inks] == ["silver_nitrate", "ascorbate"]
    assert ag.conductivity_s_per_m == 1.42e5 and ag.bulk_conductivity_s_per_m == 6.1e7
    (flash,) = ag.post_steps
    assert flash.kind == "flash_heat" and flash.temperature_c == 150.0 and flash.duration_s == 60.0
    assert [i.name for i in lib["epoxy"].inks] == ["polyepoxide", "diamine"]
    assert any("stability" in w for w in lib["epoxy"].warnings)
    assert [i.name for i in lib["polyamide"].inks] == ["acyl_thiol", "polyamine"]
    assert lib["polyamide"].conductivity_s_per_m is None


def test_build_formulas_match_the_worked_examples():
    d = drops_per_mm2(360, 360)
    assert wet_film_um(10.0, d) == pytest.approx(2.0, abs=0.01)  # 10 pL at 360 x 360 dpi: 2.0 um
    silver = builtin_library()["silver"]
    t_nm = float(cycle_thickness_um(silver, 10.0, d)) * 1000
    assert t_nm == pytest.approx(21, abs=0.5)  # 1 M silver nitrate: about 21 nm per pass
    # limiting reactant: halve the ascorbate and the silver formed halves
    weak = silver.model_copy(update={"inks": (silver.inks[0], silver.inks[1].model_copy(update={"concentration_mol_per_l": 0.25}))})
    assert float(cycle_thickness_um(weak, 10.0, d)) * 1000 == pytest.approx(t_nm / 2)
    # repeats multiply the moles an ink brings
    assert moles_per_m2(10.0, 1.0, d, repeats=3) == pytest.approx(3 * moles_per_m2(10.0, 1.0, d))
    assert cycles_for_height(20.0, 0.7) == 29 and cycles_for_height(0.7, 0.7) == 1


def test_build_user_materials_from_toml(tmp_path):
    p = tmp_path / "mats.toml"
    p.write_text(
        '[materials.silver]\nproduct = { name = "Ag", molar_mass_g_per_mol = 107.87, density_g_per_cm3 = 10.49 }\n'
        'conductivity_s_per_m = 8.06e5\n[[materials.silver.inks]]\nname = "nitrate_2M"\nconcentration_mol_per_l = 2.0\n'
        '[materials.carbon]\nproduct = { name = "C", molar_mass_g_per_mol = 12.0, density_g_per_cm3 = 1.8, porosity = 0.5 }\n'
        'conductivity_s_per_m = 1e3\n[[materials.carbon.inks]]\nname = "carbon_ink"\nconcentration_mol_per_l = 5\n',
        encoding="utf-8",
    )
    lib = load_materials(p)
    assert lib["silver"].conductivity_s_per_m == 8.06e5 and lib["silver"].inks[0].name == "nitrate_2M"
    assert lib["carbon"].product.porosity == 0.5 and "plaster" in lib


@pytest.mark.parametrize(
    "text, where",
    [
        ('[materials.x]\nproduct = { name = "a", molar_mass_g_per_mol = -1, density_g_per_cm3 = 1 }\n[[materials.x.inks]]\nname = "i"\nconcentration_mol_per_l = 1\n',
         "materials.x.product.molar_mass_g_per_mol"),
        ('[materials.x]\nproduct = { name = "a", molar_mass_g_per_mol = 1, density_g_per_cm3 = 1 }\n', "materials.x.inks"),
        ('[materials.x]\nproduct = { name = "a", molar_mass_g_per_mol = 1, density_g_per_cm3 = 1 }\n[[materials.x.inks]]\nname = "i"\nconcentration_mol_per_l = 1\nrepeats = 0\n',
         "materials.x.inks[0].repeats"),
        ("[materials.x\n", "not valid TOML"),
    ],
)
def test_build_bad_user_materials_name_the_field(tmp_path, text, where):
    p = tmp_path / "m.toml"
    p.write_text(text, encoding="utf-8")
    with pytest.raises(ConfigError) as ei:
        load_materials(p)
    assert where in str(ei.value) and str(p) in str(ei.value)
