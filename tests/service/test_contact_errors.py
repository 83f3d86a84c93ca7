"""A wheel that cannot make contact (physics ``NoContactError``) becomes a 422 naming the field."""

from wearcast.physics.contact.locus import NoContactError
from wearcast.service.errors import from_value_error


def test_no_contact_error_maps_to_422_naming_the_field():
    error = from_value_error(NoContactError("wheel", "no approach carries the wheel load"),
                             prefix="profile")
    assert error.status == 422
    assert "wheel" in str(error.item())
    assert "no approach carries the wheel load" in str(error.item())
