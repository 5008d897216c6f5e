"""Images of every common kind reach the planner and a server as the picture a viewer shows, or are refused."""

from __future__ import annotations

import base64
import io

import numpy as np
import pytest
from PIL import Image

from legged_gente.generation.backends.image import LEGEND, plan_image
from legged_gente.generation.backends.openai_backend import image_data_url

H, W = 120, 160
ORIENTATION = 0x0112


def _encode(img: Image.Image, fmt: str = "PNG", **kw) -> bytes:
    buf = io.BytesIO()
    img.save(buf, format=fmt, **kw)
    return buf.getvalue()


def _photo() -> np.ndarray:
    """A blue sky over a textured meadow with a sea band: enough structure for the photo reader."""
    rng = np.random.default_rng(0)
    im = np.zeros((H, W, 3), np.float32)
    t = (np.arange(45) / 45)[:, None, None]
    im[:45] = np.asarray((40, 90, 200)) * (1 - t) + np.asarray((170, 210, 250)) * t
    im[45:] = (70, 130, 50)
    im[45:] += rng.normal(0, 18, (H - 45, W, 3))
    im[45:80] = (30, 90, 160)
    return np.clip(im + rng.normal(0, 6, im.shape), 0, 255).astype(np.uint8)


def _calls(result):
    return [(c.tool, c.params, c.region, c.mode) for c in result.calls]


def test_transparent_pixels_are_refused_not_read_as_black():
    # A sketch painted on a transparent canvas: the unpainted half is (0, 0, 0, 0), which dropping the alpha
    # channel turns into the legend's black, a 0.5 m obstacle block over half the tile.
    sketch = np.zeros((96, 96, 4), np.uint8)
    sketch[:, :48] = (*LEGEND["water"].rgb, 255)
    with pytest.raises(ValueError, match=r"^the image has transparent pixels \(50 % of it\)"):
        plan_image(_encode(Image.fromarray(sketch, "RGBA")))
    palette = Image.fromarray(sketch[..., :3]).convert("P")
    palette.info["transparency"] = palette.getpixel((0, 95))  # the unpainted colour, transparent (tRNS)
    with pytest.raises(ValueError, match="transparent pixels"):
        plan_image(_encode(palette, transparency=palette.info["transparency"]))
    opaque = sketch.copy()
    opaque[..., 3] = 255  # an alpha channel that hides nothing changes nothing
    assert _calls(plan_image(_encode(Image.fromarray(opaque, "RGBA")))) == _calls(plan_image(_encode(Image.fromarray(opaque[..., :3]))))


def test_a_16_bit_grey_picture_reads_as_its_8_bit_version():
    grey8 = _photo().mean(-1).round().astype(np.uint8)
    grey16 = Image.fromarray(grey8.astype(np.uint16) * 257)  # the same picture, full 16-bit range
    assert Image.open(io.BytesIO(_encode(grey16))).mode.startswith("I;16")
    assert _calls(plan_image(_encode(grey16))) == _calls(plan_image(_encode(Image.fromarray(grey8))))


def test_integer_or_float_pixels_beyond_8_bits_are_refused():
    wide = Image.fromarray((np.arange(H * W).reshape(H, W) * 10).astype(np.int32))  # mode I, up to 191990
    with pytest.raises(ValueError, match=r"pixels from 0 to 191990, beyond .*save it as an 8- or 16-bit PNG"):
        plan_image(_encode(wide, "TIFF"))
    unit = Image.fromarray(np.linspace(-1.0, 1.0, H * W, dtype=np.float32).reshape(H, W))  # mode F
    with pytest.raises(ValueError, match="pixels from -1 to 1"):
        plan_image(_encode(unit, "TIFF"))


def test_exif_orientation_is_applied():
    upright = Image.fromarray(_photo())
    exif = Image.Exif()
    exif[ORIENTATION] = 6  # a camera held upright stores the picture turned; a viewer turns it back
    stored = _encode(upright.transpose(Image.Transpose.ROTATE_90), "JPEG", quality=95, exif=exif.tobytes())
    assert _calls(plan_image(stored)) == _calls(plan_image(_encode(upright, "JPEG", quality=95)))


def _sent(url: str) -> tuple[str, Image.Image]:
    head, data = url.split(",", 1)
    return head, Image.open(io.BytesIO(base64.b64decode(data)))


def test_data_url_is_a_web_format_a_server_reads():
    picture = Image.fromarray(_photo())
    for fmt in ("PNG", "JPEG", "WEBP", "GIF"):  # sent as they are
        data = _encode(picture, fmt)
        assert image_data_url(data) == f"data:image/{fmt.lower()};base64,{base64.b64encode(data).decode()}"
    # A phone's JPEG with a second picture (MPO) is a JPEG: image/mpo is no type a server knows.
    mpo = _encode(picture, "MPO", save_all=True, append_images=[picture])
    assert image_data_url(mpo) == f"data:image/jpeg;base64,{base64.b64encode(mpo).decode()}"
    for fmt in ("BMP", "TIFF", "ICO", "PPM"):  # re-encoded losslessly as PNG
        head, sent = _sent(image_data_url(_encode(picture, fmt)))
        assert head == "data:image/png;base64" and sent.format == "PNG", fmt
        assert np.array_equal(np.asarray(sent.convert("RGB")), np.asarray(picture)) or fmt == "ICO"


def test_data_url_is_sent_upright():
    picture = Image.fromarray(_photo())
    exif = Image.Exif()
    exif[ORIENTATION] = 6
    head, sent = _sent(image_data_url(_encode(picture.transpose(Image.Transpose.ROTATE_90), "JPEG", quality=95,
                                              exif=exif.tobytes())))
    assert head == "data:image/jpeg;base64" and sent.size == picture.size
    assert sent.getexif().get(ORIENTATION, 1) == 1
    assert np.abs(np.asarray(sent, np.float32) - np.asarray(picture, np.float32)).mean() < 8  # JPEG twice


def test_a_sketch_block_thinner_than_a_cell_is_skipped_with_a_warning():
    from legged_gente.generation.pipeline import generate_spec

    sketch = np.full((96, 96, 3), LEGEND["grass"].rgb, np.uint8)
    sketch[40:42, 40:42] = LEGEND["obstacle"].rgb  # 0.42 m on a 20 m tile: no cell of 1 m lies in it
    spec, result = generate_spec(image=_encode(Image.fromarray(sketch)), resolution=1.0)
    assert [c.tool for c in spec.calls] == ["natural_ground"]
    assert any(w.startswith("skipped: flat: region") and "holds no cell at resolution 1.0 m" in w for w in result.warnings)
    spec, result = generate_spec(image=_encode(Image.fromarray(sketch)), resolution=0.1)
    assert [c.tool for c in spec.calls] == ["natural_ground", "flat"] and not result.warnings


def test_running_out_of_memory_while_decoding_is_not_called_an_unreadable_file(monkeypatch):
    from legged_gente.generation.backends import image as image_module

    def out_of_memory(*args, **kwargs):
        raise MemoryError

    monkeypatch.setattr(image_module.Image, "open", out_of_memory)
    with pytest.raises(MemoryError):
        image_module.open_image(b"\x89PNG\r\n\x1a\n", "big.png")


@pytest.mark.parametrize("fmt", ["PNG", "JPEG"])
def test_a_truncated_image_is_refused_saying_so(fmt):
    """A PNG or JPEG cut short (an interrupted copy) was refused as '(OSError); pass a PNG or JPEG file', which it
    is: Pillow's own reason, that the file is truncated, was dropped."""
    from legged_gente.generation.backends.image import open_image

    data = _encode(Image.fromarray(_photo()), fmt)
    with pytest.raises(ValueError) as refused:
        open_image(data[: len(data) // 2], "photo")
    assert str(refused.value).startswith("photo could not be read as an image (OSError: image file is truncated")
