//! A calibration data set: the template and the points of every image,
//! read from files or given in memory, validated (docs/model.md §1 turns
//! electrode amplitudes into impact points), with what was dropped.

use std::path::{Path, PathBuf};

use psdcal_io::{
    validate_data_set, DataSetSummary, DataSetValidator, GainsFile, Observations, Signals,
    Template, ValidatedDataSet, ValidationOptions, Warning,
};
use psdcal_model::{ChannelGains, PsdGeometry};

use crate::base::error::Result;
use crate::base::provenance::InputHashes;

/// Where a data set's points come from.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum PointSource {
    /// observations.csv: measured impact points.
    Observations(PathBuf),
    /// signals.csv: electrode amplitudes.
    Signals(PathBuf),
}

/// The files of a data set.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct DataSetFiles {
    /// template.csv.
    pub template: PathBuf,
    /// observations.csv or signals.csv.
    pub points: PointSource,
    /// gains.json of an electrical calibration (with signals only): divided
    /// out of the amplitudes and held fixed.
    pub gains: Option<PathBuf>,
}

/// How a data set is read and validated (default: 9 × 9 mm, not strict,
/// the default read limits).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct LoadOptions {
    /// The PSD's active area.
    pub geometry: PsdGeometry,
    /// Every warning is an error instead of dropping the data.
    pub strict: bool,
    /// Bounds on the files read whole (docs/formats.md, "Limits").
    pub limits: psdcal_io::ReadLimits,
}

/// The points of a data set given in memory.
#[derive(Debug, Clone, PartialEq)]
pub enum MemoryPoints {
    /// Measured impact points.
    Observations(Observations),
    /// Electrode amplitudes, with the known gains to divide out (if any).
    Signals(Signals, Option<ChannelGains>),
}

/// A validated data set.
#[derive(Debug, Clone, PartialEq)]
pub struct DataSet {
    /// The template.
    pub template: Template,
    /// Every observation read (impact points; from amplitudes when the
    /// source was signals). Empty for an observations.csv read by
    /// [`Self::from_files`]: its rows are validated as they are read and
    /// only the usable points kept (`validated`), so memory follows the
    /// points, not the file's text.
    pub observations: Observations,
    /// The number of rows of the points file (or in memory).
    pub rows: usize,
    /// The amplitudes, when the source was signals.
    pub signals: Option<Signals>,
    /// Known gains divided out of the amplitudes (from a gains file).
    pub known_gains: Option<ChannelGains>,
    /// The usable points by image, and the warnings.
    pub validated: ValidatedDataSet,
    /// The options it was validated with.
    pub options: LoadOptions,
    /// The input files and their SHA-256 (empty for a data set in memory).
    pub inputs: InputHashes,
}

impl DataSet {
    /// Reads and validates the files.
    pub fn from_files(files: &DataSetFiles, options: &LoadOptions) -> Result<Self> {
        // Each file is read once; its hash is of the bytes parsed.
        let mut inputs = InputHashes::default();
        let limits = options.limits;
        let template = inputs.read(&files.template, |s, r| {
            Template::from_reader_with(s, r, limits)
        })?;
        let known: Option<GainsFile> = match &files.gains {
            Some(path) => {
                Some(inputs.read(path, |s, r| GainsFile::from_reader_with(s, r, limits))?)
            }
            None => None,
        };
        let points = match &files.points {
            PointSource::Observations(path) => {
                return Self::streamed(template, path, options, inputs);
            }
            PointSource::Signals(path) => MemoryPoints::Signals(
                inputs.read(path, |s, r| Signals::from_reader_with(s, r, limits))?,
                known.map(|g| g.gains()),
            ),
        };
        let mut set = Self::from_memory(template, points, options)?;
        set.inputs = inputs;
        Ok(set)
    }

    /// observations.csv checked row by row as it is read
    /// ([`DataSetValidator`]): no row is kept as text.
    fn streamed(
        template: Template,
        path: &Path,
        options: &LoadOptions,
        mut inputs: InputHashes,
    ) -> Result<Self> {
        let source = path.display().to_string();
        let mut validator = DataSetValidator::new(&template, &source, &validation(options));
        let rows = inputs.read(path, |s, r| {
            Observations::for_each_row(s, r, options.limits, |row| validator.push(row))
        })?;
        let validated = validator.finish()?;
        Ok(Self {
            template,
            observations: Observations {
                source,
                rows: Vec::new(),
            },
            rows,
            signals: None,
            known_gains: None,
            validated,
            options: *options,
            inputs,
        })
    }

    /// Validates a data set given in memory.
    pub fn from_memory(
        template: Template,
        points: MemoryPoints,
        options: &LoadOptions,
    ) -> Result<Self> {
        let (observations, signals, known_gains) = match points {
            MemoryPoints::Observations(o) => (o, None, None),
            MemoryPoints::Signals(s, gains) => {
                let o =
                    s.to_observations(&options.geometry, &gains.unwrap_or(ChannelGains::UNIT))?;
                (o, Some(s), gains)
            }
        };
        let validated = validate_data_set(&template, &observations, &validation(options))?;
        Ok(Self {
            template,
            rows: observations.rows.len(),
            observations,
            signals,
            known_gains,
            validated,
            options: *options,
            inputs: InputHashes::default(),
        })
    }

    /// What was dropped, and why.
    pub fn warnings(&self) -> &[Warning] {
        &self.validated.warnings
    }

    /// What `psdcal check` reports: images, points, drops and coverage.
    pub fn summary(&self) -> DataSetSummary {
        DataSetSummary::new(
            &self.template,
            &self.observations.source,
            self.rows,
            &self.validated,
            &self.options.geometry,
        )
    }

    /// The file the points came from, as read.
    pub fn points_source(&self) -> &str {
        &self.observations.source
    }
}

/// The path of a point source.
pub fn source_path(source: &PointSource) -> &Path {
    match source {
        PointSource::Observations(p) | PointSource::Signals(p) => p,
    }
}

/// How a data set's points are checked against its template.
fn validation(options: &LoadOptions) -> ValidationOptions {
    ValidationOptions {
        geometry: options.geometry,
        strict: options.strict,
    }
}
