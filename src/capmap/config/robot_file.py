"""Files a config names, as files: the URDF a robot file names (a path beside it or in a pip package),
the meshes that URDF names (found as Pinocchio finds them), their checks (regular, bounded, readable:
one :class:`capmap.errors.ConfigError` line naming the file and the key) and the list a content hash
must cover. No robot is built here: robot files become robots in :mod:`capmap.robots`."""

from __future__ import annotations

import os
from importlib import metadata
from pathlib import Path
from xml.etree import ElementTree

from capmap.config.validation import load_yaml, read_regular_file
from capmap.errors import ConfigError

__all__ = ["package_file", "referenced_files", "check_urdf", "urdf_package_dir", "mesh_search_dirs", "check_meshes",
           "MAX_URDF_BYTES", "MAX_MESH_BYTES", "MESH_SUFFIXES"]

_YAML_SUFFIXES = (".yaml", ".yml")


MAX_URDF_BYTES = 64 * 1024 * 1024  # 64 MiB: a URDF is text; its meshes are separate files
MAX_MESH_BYTES = 256 * 1024 * 1024  # a collision mesh (Baxter's largest: ~2 MB)
MESH_SUFFIXES = frozenset({".dae", ".stl", ".obj", ".ply", ".off", ".3ds", ".fbx", ".glb", ".gltf"})  # assimp's usual


def package_file(package: str, path: str, source: str) -> Path:
    """A file shipped by an installed pip distribution (e.g. example-robot-data's URDFs), found by
    the end of its installed path, so the distribution's own prefix layout does not matter."""
    try:
        dist = metadata.distribution(package)
    except metadata.PackageNotFoundError:
        raise ConfigError(f"{source}: urdf.package = {package!r} is not installed (pip install {package})") from None
    want = "/" + path.strip("/")
    hits = [f for f in (dist.files or []) if ("/" + str(f)).endswith(want)]
    if len(hits) != 1:
        raise ConfigError(f"{source}: urdf.path = {path!r}: {len(hits)} files of {package} end with it (need one)")
    return Path(dist.locate_file(hits[0]))


def check_urdf(path: Path, source: str) -> None:
    """A URDF is well-formed XML with a <robot> root and links (before Pinocchio's C++ parser
    sees it and prints its own noise): else one :class:`ConfigError` line naming the file."""
    try:
        data = read_regular_file(path, MAX_URDF_BYTES)  # never a FIFO or device, bounded
    except ConfigError as exc:
        raise ConfigError(f"{source}: urdf {exc}") from None
    try:
        root = ElementTree.fromstring(data)
    except ElementTree.ParseError as exc:
        raise ConfigError(f"{source}: urdf {path}: not valid XML ({exc})") from None
    if root.tag != "robot" or root.find("link") is None:
        raise ConfigError(f"{source}: urdf {path}: not a URDF (root <{root.tag}>, needs <robot> with <link>s)")


def urdf_package_dir(urdf_path: Path) -> Path:
    """The package directory the dual-arm loader gives Pinocchio for a URDF's mesh names: the
    nearest enclosing ``share`` folder (an installed package's data prefix, where
    ``package://example-robot-data/...`` resolves), else the URDF's own folder."""
    return next((p for p in Path(urdf_path).parents if p.name == "share"), Path(urdf_path).parent)


def mesh_search_dirs(package_dirs) -> list[str]:
    """Where Pinocchio looks for a ``package://`` / ``model://`` or relative mesh name, in order:
    the given package directories, then each entry of ``$ROS_PACKAGE_PATH``, then ``<entry>/share``
    of each of ``$AMENT_PREFIX_PATH`` (which Pinocchio appends itself, empty entries included)."""
    env = {k: os.environ[k].split(os.pathsep) for k in ("ROS_PACKAGE_PATH", "AMENT_PREFIX_PATH") if k in os.environ}
    return ([str(d) for d in package_dirs] + env.get("ROS_PACKAGE_PATH", [])
            + [p + "/share" for p in env.get("AMENT_PREFIX_PATH", [])])


def _meshes(urdf_path: Path) -> list[str]:
    """The mesh names (``filename``) of a URDF's collision and visual geometry, once each in order ([]
    when it is not readable XML: the loaders report that). A dual-arm robot loads both (its capsules
    cover the visual meshes as well as the collision geometry)."""
    try:
        root = ElementTree.parse(urdf_path).getroot()
    except (ElementTree.ParseError, OSError):
        return []
    names = []
    for element in (c for link in root.findall("link") for kind in ("collision", "visual") for c in link.findall(kind)):
        geometry = element.find("geometry")
        shape = next(iter(geometry), None) if geometry is not None else None  # urdfdom reads the first shape
        if shape is not None and shape.tag == "mesh" and shape.get("filename") and shape.get("filename") not in names:
            names.append(shape.get("filename"))
    return names


def _find_mesh(name: str, dirs: list[str]) -> Path:
    """The file Pinocchio reads for mesh ``name`` (its ``retrieveResourcePath``); LookupError saying why
    there is none (not found in ``dirs``, a scheme it does not handle)."""
    scheme, sep, rest = name.partition("://")
    if sep and scheme == "file":
        return Path(rest)
    if sep and scheme not in ("package", "model"):
        raise LookupError(f"scheme {scheme}:// is not handled")
    if sep or not Path(name).is_absolute():
        rest = rest if sep else name
        hit = next((f"{d}/{rest}" for d in dirs if os.path.exists(f"{d}/{rest}")), None)
        if hit is None:
            raise LookupError(f"not found in {', '.join(dirs) or 'no package directory'}")
        return Path(hit)
    return Path(name)


def check_meshes(urdf_path: str | Path, package_dirs, source: str) -> list[Path]:
    """Every mesh a URDF names (collision and visual), found as Pinocchio finds it (:func:`mesh_search_dirs` of
    ``package_dirs``); returns the files. A mesh not found, not a regular file or unreadable is one
    :class:`ConfigError` line naming the robot file, the URDF and the mesh."""
    dirs, out = mesh_search_dirs(package_dirs), []
    for name in _meshes(Path(urdf_path)):
        where = f"{source}: urdf {urdf_path}: mesh {name!r}"
        try:
            path = _find_mesh(name, dirs)
        except LookupError as exc:
            raise ConfigError(f"{where}: {exc}") from None
        if not path.is_file():
            raise ConfigError(f"{where}: {path} is {'not a regular file' if path.exists() else 'missing'}")
        if path.suffix.lower() not in MESH_SUFFIXES:
            raise ConfigError(f"{where}: {path} is not a mesh file ({', '.join(sorted(MESH_SUFFIXES))})")
        if path.stat().st_size > MAX_MESH_BYTES:
            raise ConfigError(f"{where}: {path} is larger than {MAX_MESH_BYTES >> 20} MiB")
        try:
            with open(path, "rb") as f:
                f.read(1)
        except OSError as exc:
            raise ConfigError(f"{where}: {path}: cannot read ({exc.strerror})") from None
        out.append(path)
    return out


def _mesh_files(urdf_path: Path) -> list[Path]:
    """The collision and visual meshes of a dual-arm URDF that exist (missing ones are left to :func:`check_meshes`)."""
    dirs, out = mesh_search_dirs([urdf_package_dir(urdf_path)]), []
    for name in _meshes(urdf_path):
        try:
            out.append(_find_mesh(name, dirs))
        except LookupError:
            continue
    return [p for p in out if p.is_file()]


def referenced_files(path: str | Path) -> list[Path]:
    """A robot, dual-arm or platform file, the URDF it names (if any) and, for a dual-arm file (one
    with ``capsules``: the only robots whose geometry is loaded), the URDF's collision and visual meshes
    (:func:`check_meshes`): what its content hash must cover. A file that is not YAML (``.yaml``,
    ``.yml``), e.g. a point cloud, is returned alone and not parsed. Unreadable or malformed files
    are left to the loaders' one-line errors."""
    path = Path(path)
    out = [path]
    if path.suffix.lower() not in _YAML_SUFFIXES:
        return out
    try:
        doc = load_yaml(path)
    except ConfigError:
        return out
    urdf = doc.get("urdf") if isinstance(doc, dict) else None
    if isinstance(urdf, dict) and isinstance(urdf.get("path"), str):
        try:
            target = (package_file(urdf["package"], urdf["path"], str(path)) if "package" in urdf
                      else (path.parent / urdf["path"]))
        except ConfigError:
            return out
        if target.is_file():
            out.append(target)
            if "capsules" in doc:
                out += _mesh_files(target)
    return out
